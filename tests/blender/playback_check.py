"""Run inside real Blender by blender_playback_test.sh:

    blender -b --factory-startup --python-exit-code 1 --python playback_check.py -- \
        --zip ADDON_ZIP --shot OUT/demo --expected EXPECTED.json --frames A,B,C --blend CLI.blend \
        [--obj-shot OBJ_OUT/demo] [--ours-shot OURS_OUT/demo]

Installs the add-on from its zip (into BLENDER_USER_SCRIPTS, a private folder the shell test
sets), imports the shot with the File > Import operator, and checks at the frames given: the
evaluated boundary and crack meshes against EXPECTED.json (vertex and face counts, position sums,
UVs and vertex colors of vertex 0, read from the files with pipeline/io's assimp reader; the
face attribute "piece": its distinct ids, their sum and the faces' sum), an empty crack mesh
where the manifest has no crack file, the debris object (point count and the sums of velocity,
pscale, id and piece, read with pipeline/io's debris reader) when the shot wrote debris and
none when it did not, Object > Separate mudcrack pieces at the last frame, the material wiring,
the scene's frame range and fps, y-up to z-up, the handler registered once, the LRU cache, the
same frames written as .obj (no fragment ids, no debris) and by the `ours` surfacing (many
piece ids, also separated), and the .blend that the CLI script saved (handlers after a file
load). Any failed check raises: exit status 1.
"""
import argparse
import json
import math
import os
import sys

import bpy
from mathutils import Vector

failures = []


def check(condition, message):
    if not condition:
        failures.append(message)
        print(f"FAIL: {message}", file=sys.stderr)
    return condition


def close(a, b, tol):
    return abs(a - b) <= tol


def args():
    p = argparse.ArgumentParser()
    p.add_argument("--zip", required=True)
    p.add_argument("--shot", required=True)
    p.add_argument("--expected", required=True)
    p.add_argument("--frames", required=True)
    p.add_argument("--blend", required=True)
    p.add_argument("--obj-shot", help="the same frames surfaced with /surfacing/format obj")
    p.add_argument("--ours-shot", help="the same frames surfaced with /surfacing/mode ours")
    return p.parse_args(sys.argv[sys.argv.index("--") + 1:])


def handler_count():
    return sum(1 for h in bpy.app.handlers.frame_change_pre if getattr(h, "__name__", "") == "mudcrack_frame_change")


def has_debris(manifest):
    return any((e.get("debris") or {}).get("file") for e in manifest["per_frame"])


def shot_objects(scene, manifest_path, manifest):
    """{kind: object} of the scene's mudcrack objects of a shot; exactly one per kind, and a
    debris object exactly when the shot wrote debris files."""
    found = {}
    for obj in scene.objects:
        kind = obj.get("mudcrack_kind")
        if kind is not None and os.path.realpath(obj.get("mudcrack_manifest", "")) == os.path.realpath(manifest_path):
            check(kind not in found, f"two objects of kind {kind}: {found.get(kind) and found[kind].name}, {obj.name}")
            found[kind] = obj
    kinds = {"boundary", "crack"} | ({"debris"} if has_debris(manifest) else set())
    check(set(found) == kinds, f"mudcrack objects {sorted(found)}: expected {sorted(kinds)}")
    return found


def attribute_values(me, name, data_type, domain):
    """The values of a mesh attribute as a flat list, or None (a failed check) when the mesh has
    no such attribute of that type and domain."""
    attr = me.attributes.get(name)
    where = f"attribute '{name}'"
    if not check(attr is not None, f"{where}: missing (attributes: {sorted(a.name for a in me.attributes)})"):
        return None
    if not check(attr.data_type == data_type and attr.domain == domain,
                 f"{where}: {attr.data_type} on {attr.domain}, expected {data_type} on {domain}"):
        return None
    width = 3 if data_type == "FLOAT_VECTOR" else 1
    values = [0] * (width * len(attr.data)) if data_type == "INT" else [0.0] * (width * len(attr.data))
    attr.data.foreach_get("vector" if width == 3 else "value", values)
    return values


def check_debris_shown(obj, depsgraph, want, where):
    """The debris object evaluates to one point per grain of radius pscale (its Geometry Nodes
    modifier), so it shows in the viewport and in renders."""
    clouds = [i.object.data for i in depsgraph.object_instances
              if i.is_instance and i.parent and i.parent.original == obj and i.object.type == "POINTCLOUD"]
    points = sum(len(c.points) for c in clouds)
    radii = math.fsum(p.radius for c in clouds for p in c.points)
    check(points == want["points"] and close(radii, want["pscale_sum"], 1e-6 * points + 1e-9),
          f"{where}: shown as {points} points of radius sum {radii}; the file has {want['points']} "
          f"of pscale sum {want['pscale_sum']}")


def check_pieces(me, want, where):
    """The face attribute "piece" against the file's fragment ids (mesh_info's piece keys)."""
    if "pieces" not in want:  # no fragment ids in the file (obj): no attribute either
        check(me.attributes.get("piece") is None, f"{where}: a 'piece' attribute from a file without fragment ids")
        return
    pieces = attribute_values(me, "piece", "INT", "FACE")
    if pieces is None:
        return
    ids = set(pieces)
    check(len(ids) == want["pieces"] and sum(ids) == want["piece_id_sum"],
          f"{where}: {len(ids)} distinct pieces (id sum {sum(ids)}); the file has {want['pieces']} "
          f"(id sum {want['piece_id_sum']})")
    check(sum(pieces) == want["piece_face_sum"],
          f"{where}: faces' piece sum {sum(pieces)} != the file's {want['piece_face_sum']} (faces in the wrong piece)")


def check_debris(me, want, entry, where):
    """A debris mesh against the file (mesh_info's debris keys) and the manifest's point count."""
    n = len(me.vertices)
    check(n == want["points"] and n == entry["debris"]["points"] and len(me.polygons) == 0 and len(me.edges) == 0,
          f"{where}: {n} vertices, {len(me.edges)} edges, {len(me.polygons)} faces; the file has {want['points']} "
          f"points, the manifest says {entry['debris']['points']} (points only)")
    if n != want["points"]:
        return
    co = [0.0] * (3 * n)
    me.vertices.foreach_get("co", co)
    velocity = attribute_values(me, "velocity", "FLOAT_VECTOR", "POINT")
    for name, values in (("position", co), ("velocity", velocity)):
        if values is None:
            continue
        sums = [math.fsum(values[k::3]) for k in range(3)]
        check(all(close(sums[k], want[f"{name}_sum"][k], 1e-5 * n + 1e-6) for k in range(3)),
              f"{where}: {name} sum {sums} != the file's {want[name + '_sum']}")
    pscale = attribute_values(me, "pscale", "FLOAT", "POINT")
    if pscale is not None:
        check(close(math.fsum(pscale), want["pscale_sum"], 1e-6 * n + 1e-9) and min(pscale, default=1) > 0,
              f"{where}: pscale sum {math.fsum(pscale)} != the file's {want['pscale_sum']} (or a radius <= 0)")
    for name in ("id", "piece"):
        values = attribute_values(me, name, "INT", "POINT")
        if values is not None:
            check(sum(values) == want[f"{name}_sum"],
                  f"{where}: {name} sum {sum(values)} != the file's {want[name + '_sum']}")


def upstream_nodes(socket):
    """Every node feeding a socket, transitively."""
    seen, stack = [], [link.from_node for link in socket.links]
    while stack:
        node = stack.pop()
        if node in seen:
            continue
        seen.append(node)
        for s in node.inputs:
            stack.extend(link.from_node for link in s.links)
    return seen


def check_frame(scene, objects, frame, manifest, expected, label):
    scene.frame_set(frame)
    check(scene.frame_current == frame, f"{label}: frame_set({frame}) left frame {scene.frame_current}")
    depsgraph = bpy.context.evaluated_depsgraph_get()
    entry = next(e for e in manifest["per_frame"] if e["frame"] == frame)
    for kind, obj in objects.items():
        file = (entry.get(kind) or {}).get("file")
        # the debris object's modifier turns its vertices into points: its own mesh holds them
        me = obj.data if kind == "debris" else obj.evaluated_get(depsgraph).data
        where = f"{label}: frame {frame}: {kind}"
        if file is None:
            check(len(me.vertices) == 0 and len(me.polygons) == 0,
                  f"{where}: no {kind} file in the manifest, but the mesh has {len(me.vertices)} vertices "
                  f"and {len(me.polygons)} faces (expected an empty mesh, not an earlier frame's)")
            continue
        want = expected[os.path.join(manifest["_dir"], file)]
        if kind == "debris":
            check_debris(me, want, entry, where)
            check_debris_shown(obj, depsgraph, want, where)
            continue
        got_v, got_f = len(me.vertices), len(me.polygons)
        check(got_v == want["vertices"] and got_f == want["faces"],
              f"{where}: {got_v} vertices, {got_f} faces; {file} has {want['vertices']} and {want['faces']}")
        check(got_f == entry[kind]["faces"], f"{where}: {got_f} faces; the manifest says {entry[kind]['faces']}")
        if got_v != want["vertices"] or got_v == 0:
            continue
        check(all(len(p.vertices) == 3 for p in me.polygons[:1000]), f"{where}: faces are not triangles")
        check_pieces(me, want, where)
        # positions as in the file (object space: the root turns y-up into z-up)
        sums = [0.0, 0.0, 0.0]
        co = [0.0] * (3 * got_v)
        me.vertices.foreach_get("co", co)
        for k in range(3):
            sums[k] = math.fsum(co[k::3])
        for k in range(3):
            check(close(sums[k], want["position_sum"][k], 1e-5 * got_v + 1e-6),
                  f"{where}: position sum {sums} != {want['position_sum']} (the file's)")
        # UV channel 0 present on every corner, and vertex 0's UV as the file holds it
        check(len(me.uv_layers) >= 1 and me.uv_layers[0].name == "UVMap",
              f"{where}: UV layers {[l.name for l in me.uv_layers]}: expected UVMap first (channel 0)")
        if want["uvs"] and me.uv_layers:
            uv = me.uv_layers[0].data
            check(len(uv) == 3 * got_f, f"{where}: {len(uv)} UV corners for {got_f} triangles")
            corner = next(i for i, l in enumerate(me.loops) if l.vertex_index == 0)
            got = tuple(uv[corner].uv)
            check(close(got[0], want["uv0"][0], 1e-5) and close(got[1], want["uv0"][1], 1e-5),
                  f"{where}: vertex 0's UV {got} != {want['uv0']} (the file's, v up)")
        # vertex colors: (saturation, logistic(alpha), 0, 1)
        attr = me.color_attributes.get("Col")
        if check(attr is not None and attr.domain == "POINT", f"{where}: no per-vertex color attribute 'Col'"):
            c = tuple(attr.data[0].color)
            check(close(c[0], want["color0"][0], 1e-4) and close(c[1], want["color0"][1], 1e-4),
                  f"{where}: vertex 0's color {c[:2]} != {want['color0']} (saturation, logistic(alpha))")
        check(len(me.materials) == 1 and me.materials[0] is not None and
              me.materials[0].get("mudcrack_material") == kind,
              f"{where}: materials {[m and m.name for m in me.materials]}: expected the {kind} material")


def check_separated_pieces(scene, objects, frame, manifest, expected):
    """The operator's objects at `frame`: named piece_<id>, each face of its piece, soil faces in
    the soil material's slot and walls in the crack's, and together every face of the frame's
    boundary and crack files once (face counts and the faces' piece sums of mesh_info)."""
    scene.frame_set(frame)
    entry = next(e for e in manifest["per_frame"] if e["frame"] == frame)
    wants = {kind: expected[os.path.join(manifest["_dir"], entry[kind]["file"])]
             for kind in ("boundary", "crack") if (entry.get(kind) or {}).get("file")}
    bpy.context.view_layer.objects.active = objects["boundary"]
    before = set(bpy.data.objects)
    result = bpy.ops.object.mudcrack_separate_pieces()
    check(result == {"FINISHED"}, f"object.mudcrack_separate_pieces returned {result}")
    made = [o for o in bpy.data.objects if o not in before]
    check(all("mudcrack_piece" in o and o.get("mudcrack_frame") == frame for o in made),
          "separating pieces made objects that are not pieces of the frame")
    faces = {"boundary": 0, "crack": 0}
    face_sums = {"boundary": 0, "crack": 0}
    for obj in made:
        piece = obj["mudcrack_piece"]
        where = f"separated {obj.name}"
        # (Blender appends .001 to the name when an earlier separation holds it)
        check(obj.name.split(".")[0] == f"piece_{piece}", f"{where}: expected the name piece_{piece}")
        check(obj.parent is not None and obj.parent == objects["boundary"].parent,
              f"{where}: not under the shot's root")
        me = obj.data
        pieces = attribute_values(me, "piece", "INT", "FACE")
        check(pieces is not None and set(pieces) == {piece}, f"{where}: faces of pieces {set(pieces or [])}")
        slots = [0] * len(me.polygons)
        me.polygons.foreach_get("material_index", slots)
        kinds = [m.get("mudcrack_material") for m in me.materials]
        for slot, kind in enumerate(kinds):
            n = slots.count(slot)
            faces[kind] = faces.get(kind, 0) + n
            face_sums[kind] = face_sums.get(kind, 0) + n * piece
    for kind, want in wants.items():
        check(faces[kind] == want["faces"] and face_sums[kind] == want["piece_face_sum"],
              f"separated pieces at frame {frame}: {faces[kind]} {kind} faces (piece sum {face_sums[kind]}); "
              f"the file has {want['faces']} ({want['piece_face_sum']})")
    check(len(made) >= max(w["pieces"] for w in wants.values()),
          f"separated pieces at frame {frame}: {len(made)} objects for {[w['pieces'] for w in wants.values()]} pieces")


def check_material(mat, kind):
    where = f"material {mat.name if mat else None} ({kind})"
    if not check(mat is not None and mat.use_nodes, f"{where}: missing or without nodes"):
        return None
    bsdf = next((n for n in mat.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled"), None)
    out = next((n for n in mat.node_tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial"), None)
    if not check(bsdf is not None and out is not None, f"{where}: no Principled BSDF or output"):
        return None
    check(any(l.from_node == bsdf for l in out.inputs["Surface"].links), f"{where}: the BSDF is not the output")
    base = bsdf.inputs["Base Color"]
    check(base.is_linked, f"{where}: Base Color is not connected")
    colors = [n for n in upstream_nodes(base) if n.bl_idname in ("ShaderNodeVertexColor", "ShaderNodeAttribute")]
    names = [getattr(n, "layer_name", None) or getattr(n, "attribute_name", None) for n in colors]
    check("Col" in names, f"{where}: Base Color is not fed by the vertex colors 'Col' (found {names})")
    rough = [n for n in upstream_nodes(bsdf.inputs["Roughness"]) if n.bl_idname == "ShaderNodeVertexColor"]
    check(rough, f"{where}: Roughness does not follow the vertex colors (wet soil glossier)")
    albedo = mat.node_tree.nodes.get("mudcrack albedo")
    check(albedo is not None, f"{where}: no 'mudcrack albedo' node")
    darkening = mat.node_tree.nodes.get("mudcrack moisture darkening")
    if check(darkening is not None, f"{where}: no moisture darkening node"):
        # color = albedo (s * k + 1) with k < 0: wet (s = 1) darker than dry (s = 0)
        check(darkening.operation == "MULTIPLY_ADD" and darkening.inputs[1].default_value < 0 and
              darkening.inputs[0].is_linked, f"{where}: saturation does not darken the albedo")
    return sum(albedo.inputs[0].default_value) if albedo else None


def read_manifest(shot_dir):
    path = os.path.join(shot_dir, "surface", "manifest.json")
    with open(path) as f:
        manifest = json.load(f)
    manifest["_dir"] = os.path.dirname(path)
    return path, manifest


def main():
    a = args()
    with open(a.expected) as f:
        expected = json.load(f)
    manifest_path, manifest = read_manifest(a.shot)
    with open(os.path.join(a.shot, "sim", "manifest.json")) as f:
        fps = json.load(f)["frames"]["fps"]
    frames = [int(x) for x in a.frames.split(",")]

    # 1. install the zip as a user would, enable it (twice: registered once)
    user_scripts = os.environ.get("BLENDER_USER_SCRIPTS", "")
    check(user_scripts and os.path.isdir(user_scripts), "BLENDER_USER_SCRIPTS must name the test's private folder")
    bpy.ops.preferences.addon_install(filepath=a.zip, overwrite=True)
    bpy.ops.preferences.addon_enable(module="mudcrack_blender")
    import mudcrack_blender
    check(os.path.realpath(mudcrack_blender.__file__).startswith(os.path.realpath(user_scripts)),
          f"the add-on was imported from {mudcrack_blender.__file__}, not from the installed zip")
    check(mudcrack_blender.bl_info["blender"] <= bpy.app.version, "bl_info asks for a newer Blender")
    mudcrack_blender.register()
    check(handler_count() == 1, f"{handler_count()} frame_change_pre handlers after registering twice: expected 1")

    # 2. a folder that is not a shot: a clear error, nothing created
    n_objects = len(bpy.data.objects)
    try:
        bpy.ops.import_scene.mudcrack_shot(filepath=os.path.dirname(a.zip))
        check(False, "importing a folder without a manifest succeeded")
    except RuntimeError as e:
        check("manifest.json" in str(e), f"importing a non-shot folder: unclear error: {e}")
    check(len(bpy.data.objects) == n_objects, "a failed import left objects behind")

    # 3. import the shot with the File > Import operator
    result = bpy.ops.import_scene.mudcrack_shot(filepath=a.shot)
    check(result == {"FINISHED"}, f"import_scene.mudcrack_shot returned {result}")
    scene = bpy.context.scene
    objects = shot_objects(scene, manifest_path, manifest)
    check(scene.frame_start == manifest["frames"]["first"] and scene.frame_end == manifest["frames"]["last"],
          f"scene frames {scene.frame_start}-{scene.frame_end}, shot {manifest['frames']['first']}-{manifest['frames']['last']}")
    check(close(scene.render.fps / scene.render.fps_base, fps, 1e-6),
          f"scene fps {scene.render.fps / scene.render.fps_base}, shot {fps}")
    # y-up (the files) -> z-up: the file's +y is Blender's +z, the file's +z is Blender's -y
    for obj in objects.values():
        m = obj.matrix_world.to_3x3()
        up, front = m @ Vector((0, 1, 0)), m @ Vector((0, 0, 1))
        check((up - Vector((0, 0, 1))).length < 1e-6 and (front - Vector((0, -1, 0))).length < 1e-6,
              f"{obj.name}: the file's y axis maps to {tuple(up)}, z to {tuple(front)} (expected z-up)")
    check(handler_count() == 1, f"{handler_count()} frame_change_pre handlers after the import: expected 1")

    # 4. the meshes follow the frame: the last frame, a frame without cracks right after it (an
    #    empty crack mesh, not the last frame's), one with cracks, and the last frame again
    order = [frames[2], frames[0], frames[1], frames[2]]
    for frame in order:
        check_frame(scene, objects, frame, manifest, expected, "import")
    # frames without a file hold the nearest end frame outside the range
    scene.frame_set(manifest["frames"]["last"] + 5)
    check(len(objects["boundary"].data.vertices) > 0, "past the last frame: the boundary mesh is empty")

    # 5. materials: vertex colors wired, cracks darker than the soil
    soil = check_material(objects["boundary"].data.materials[0] if objects["boundary"].data.materials else None, "boundary")
    scene.frame_set(frames[2])
    crack = check_material(objects["crack"].data.materials[0] if objects["crack"].data.materials else None, "crack")
    if soil is not None and crack is not None:
        check(crack < soil, f"the crack albedo ({crack:.3f}) is not darker than the soil's ({soil:.3f})")

    # 6. Object > Separate mudcrack pieces at the last frame: one object per piece
    check_separated_pieces(scene, objects, frames[2], manifest, expected)

    # 7. the cache: revisiting a cached frame reuses its mesh; a zero budget keeps one mesh
    from mudcrack_blender import playback
    scene.frame_set(frames[1])
    mesh_at = objects["boundary"].data.name
    n_meshes = len(bpy.data.meshes)
    scene.frame_set(frames[2])
    scene.frame_set(frames[1])
    check(objects["boundary"].data.name == mesh_at and len(bpy.data.meshes) == n_meshes,
          "revisiting a cached frame built a new mesh")
    for obj in objects.values():
        obj["mudcrack_cache_mb"] = 0.0
    for frame in range(manifest["frames"]["first"], manifest["frames"]["first"] + 4):
        scene.frame_set(frame)
    boundary_meshes = [m.name for m in bpy.data.meshes if m.name.startswith(objects["boundary"].name + ".")]
    check(len(playback.cached_mesh_names(objects["boundary"])) == 1 and len(boundary_meshes) == 1,
          f"with a zero cache budget: cached {playback.cached_mesh_names(objects['boundary'])}, "
          f"boundary meshes in the file {boundary_meshes}")

    # 8. the same frames as .obj (the surface manifest picked as the file): same checks
    if a.obj_shot:
        obj_manifest_path, obj_manifest = read_manifest(a.obj_shot)
        result = bpy.ops.import_scene.mudcrack_shot(filepath=obj_manifest_path)
        check(result == {"FINISHED"}, f"importing {obj_manifest_path} returned {result}")
        obj_objects = shot_objects(scene, obj_manifest_path, obj_manifest)
        for frame in order:
            check_frame(scene, obj_objects, frame, obj_manifest, expected, "obj")

    # 9. the same frames in the `ours` surfacing: its fragments are many pieces
    if a.ours_shot:
        ours_manifest_path, ours_manifest = read_manifest(a.ours_shot)
        result = bpy.ops.import_scene.mudcrack_shot(filepath=a.ours_shot)
        check(result == {"FINISHED"}, f"importing {a.ours_shot} returned {result}")
        ours_objects = shot_objects(scene, ours_manifest_path, ours_manifest)
        for frame in order:
            check_frame(scene, ours_objects, frame, ours_manifest, expected, "ours")
        check_separated_pieces(scene, ours_objects, frames[2], ours_manifest, expected)

    # 10. the .blend saved by the CLI script: handlers survive loading a file, and still run once
    bpy.ops.wm.open_mainfile(filepath=a.blend)
    check(handler_count() == 1, f"{handler_count()} frame_change_pre handlers after opening a .blend: expected 1")
    scene = bpy.context.scene
    objects = shot_objects(scene, manifest_path, manifest)
    check(scene.frame_start == manifest["frames"]["first"] and scene.frame_end == manifest["frames"]["last"],
          "the CLI's .blend has another frame range")
    for frame in [frames[0], frames[1], frames[2]]:
        check_frame(scene, objects, frame, manifest, expected, "CLI .blend")

    if failures:
        raise SystemExit(f"{len(failures)} check(s) failed")
    print(f"playback_check: all checks passed at frames {order}")


main()
