#!/usr/bin/env bash
# Benchmarks mc-init's mesh source (input checks + CGAL Mesh_3 + boundary, UVs, rest volumes) on
# the Stanford bunny at three sizes (~10K, ~40K, ~100K particles), sequential and parallel, next
# to TetGen on the same input, and prints one table.
#
#   tools/bench_init.sh [BUILD_DIR]        (default BUILD_DIR: build)
#   EDGES=0.035,0.021,0.0156 tools/bench_init.sh build    # our target edge lengths [m]
#
# Needs BUILD_DIR/bin/init_mesh_bench (tests/init/mesh_bench.cpp), the tetgen binary (Debian
# package tetgen) and shots/assets/bunny00.off (`make assets`). The bunny is ~1 m tall.
#
# TetGen keeps every input vertex, so on the bunny (37,706 surface vertices) it cannot go below
# ~38K particles: its rows are -pY (no refinement: the input vertices only, ~our 40K row) and
# -pq3 / -pq2 (Delaunay refinement to radius-edge ratio 3 like ours, or 2: ~110-130K, ~our 100K
# row). TetGen's time is its own "Total running seconds" (reading and writing files included);
# ours excludes loading the file. CPU is user time of the whole process.
set -euo pipefail

ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-$ROOT/build}
BENCH=$BUILD/bin/init_mesh_bench
MESH=$ROOT/shots/assets/bunny00.off
EDGES=${EDGES:-0.035,0.021,0.0156}
TETGEN_SWITCHES=${TETGEN_SWITCHES:-pY pq3 pq2}

[[ -x $BENCH ]] || { echo "bench_init: $BENCH not found: build the target init_mesh_bench" >&2; exit 1; }
[[ -f $MESH ]] || { echo "bench_init: $MESH not found: run 'make assets'" >&2; exit 1; }
command -v tetgen >/dev/null || { echo "bench_init: tetgen not found: apt-get install tetgen" >&2; exit 1; }

TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

# ours: one process per size and mode, so user CPU time is per row
rows=()
for mode in sequential parallel; do
    flag=""
    [[ $mode == parallel ]] && flag="--parallel"
    IFS=, read -ra edges <<<"$EDGES"
    for e in "${edges[@]}"; do
        out="$TMP/ours_${mode}_$e"
        /usr/bin/time -f "%U" -o "$out.cpu" "$BENCH" --mesh "$MESH" --edges "$e" $flag \
            --benchmark_format=json --benchmark_out="$out.json" >/dev/null 2>&1
        rows+=("$out")
    done
done

# TetGen on a private copy (it writes its output next to the input)
cp "$MESH" "$TMP/bunny.off"
for sw in $TETGEN_SWITCHES; do
    (cd "$TMP" && /usr/bin/time -f "%U" -o "tetgen_$sw.cpu" tetgen "-${sw}V" bunny.off >"tetgen_$sw.log" 2>&1)
    rm -f "$TMP"/bunny.1.*
done

python3 - "$TMP" "$EDGES" "$TETGEN_SWITCHES" <<'EOF'
import json, re, sys, pathlib
tmp, edges, switches = pathlib.Path(sys.argv[1]), sys.argv[2].split(","), sys.argv[3].split()
head = f"{'mesher':<22} {'particles':>10} {'tets':>10} {'wall s':>8} {'cpu s':>8} {'tets/s':>10} {'particles/s':>12} {'min dihedral':>13} {'volume err %':>13} {'peak MiB':>9}"
print(head)
print("-" * len(head))
for mode in ("sequential", "parallel"):
    for e in edges:
        base = tmp / f"ours_{mode}_{e}"
        b = json.loads(pathlib.Path(f"{base}.json").read_text())["benchmarks"][0]
        cpu = float(pathlib.Path(f"{base}.cpu").read_text().split()[-1])
        wall = b["real_time"]  # seconds (the benchmark's unit)
        name = f"Mesh_3 {mode[:3]} L={float(e)*1000:g}mm"
        print(f"{name:<22} {b['particles']:>10.0f} {b['tets']:>10.0f} {wall:>8.2f} {cpu:>8.2f} {b['tets']/wall:>10.0f} "
              f"{b['particles']/wall:>12.0f} {b['min_dihedral']:>13.2f} {b['vol_err_pct']:>+13.3f} {b['peak_MiB']:>9.0f}")
for sw in switches:
    log = (tmp / f"tetgen_{sw}.log").read_text()
    cpu = float((tmp / f"tetgen_{sw}.cpu").read_text().split()[-1])
    def grab(pattern):
        m = re.search(pattern, log)
        return float(m.group(1)) if m else float("nan")
    pts, tets = grab(r"Mesh points:\s*(\d+)"), grab(r"Mesh tetrahedra:\s*(\d+)")
    wall, mind = grab(r"Total running seconds:\s*([\d.]+)"), grab(r"Smallest dihedral:\s*([\d.]+)")
    name = f"TetGen -{sw}"
    print(f"{name:<22} {pts:>10.0f} {tets:>10.0f} {wall:>8.2f} {cpu:>8.2f} {tets/wall:>10.0f} {pts/wall:>12.0f} "
          f"{mind:>13.2f} {'0 (conforms)':>13} {'':>9}")
EOF
