"""Command line entry of the mudcrack add-on, for Blender without installing it:

    blender --python tools/blender/mudcrack_blender/cli.py -- out/demo
        opens Blender with the shot imported (press Space to play)
    blender -b --factory-startup --python-exit-code 1 --python tools/blender/mudcrack_blender/cli.py -- \\
        out/demo --frame last --render still.png [--resolution 640 360] [--samples 16] [--save shot.blend]
        headless: imports, goes to a frame, renders a still with Cycles on the CPU and/or saves a .blend

SHOT is the shot's output folder (out/<shot>), its surface/ folder or surface/manifest.json.
Exit status: 0 done, 1 bad input (one line on stderr naming the file), 2 bad usage.
"""
import argparse
import os
import sys

if __package__ in (None, ""):
    # run as a plain script: import the package from the folder that holds it, without leaving
    # __pycache__ in that (source) folder
    sys.dont_write_bytecode = True
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import bpy  # noqa: E402

import mudcrack_blender  # noqa: E402
from mudcrack_blender import playback, preview  # noqa: E402
from mudcrack_blender.meshfile import MeshFileError  # noqa: E402
from mudcrack_blender.shot import DEBRIS, ShotError  # noqa: E402


def _args(argv):
    parser = argparse.ArgumentParser(
        prog="blender [-b] --python cli.py --", description="Import a mudcrack shot into Blender.")
    parser.add_argument("shot", help="out/<shot>, its surface/ folder, or surface/manifest.json")
    parser.add_argument("--frame", default="first", help="frame to show: a number, 'first' or 'last' (default first)")
    parser.add_argument("--cache-mb", type=float, default=playback.DEFAULT_CACHE_MB,
                        help=f"memory for recently shown frames per object [MB] (default {playback.DEFAULT_CACHE_MB:g})")
    parser.add_argument("--render", metavar="PNG", help="render the frame with Cycles (CPU) to this PNG")
    parser.add_argument("--resolution", type=int, nargs=2, metavar=("W", "H"), default=(640, 360))
    parser.add_argument("--samples", type=int, default=16, help="Cycles samples per pixel (default 16)")
    parser.add_argument("--threads", type=int, default=0, help="render threads (default: all)")
    parser.add_argument("--save", metavar="BLEND", help="save the scene as a .blend file")
    parser.add_argument("--keep-scene", action="store_true",
                        help="import into the open scene (default: remove the start-up cube, camera and light first)")
    args = parser.parse_args(argv)
    if args.frame not in ("first", "last"):
        try:
            args.frame = int(args.frame)
        except ValueError:
            parser.error(f"--frame {args.frame}: expected a whole number, 'first' or 'last'")
    if min(args.resolution) < 1 or args.samples < 1:
        parser.error("--resolution and --samples must be >= 1")
    return args


def _summary(kind, me):
    if kind == DEBRIS:
        return f"{kind} {len(me.vertices)} points"
    return f"{kind} {len(me.vertices)} vertices {len(me.polygons)} faces"


def main(argv):
    args = _args(argv)
    mudcrack_blender.register()
    context = bpy.context
    scene = context.scene
    if not args.keep_scene:
        for obj in list(scene.objects):
            if obj.name in ("Cube", "Camera", "Light"):
                bpy.data.objects.remove(obj)
    root, objects = playback.import_shot(context, args.shot, args.cache_mb)
    frame = {"first": scene.frame_start, "last": scene.frame_end}.get(args.frame, args.frame)
    playback.check_frame_files(playback.surface_shot(root["mudcrack_shot"]), frame)  # a damaged file: exit 1
    scene.frame_set(frame)
    print(f"mudcrack_blender: {root.name}: frames {scene.frame_start}-{scene.frame_end} at "
          f"{scene.render.fps / scene.render.fps_base:g} fps; frame {frame}: "
          + ", ".join(_summary(kind, o.data) for kind, o in objects.items()))
    if args.render:
        shot = playback.surface_shot(root["mudcrack_shot"])
        preview.stage_for_still(scene, shot, objects, *args.resolution, args.samples, args.threads)
        preview.render_still(scene, args.render)
        print(f"mudcrack_blender: wrote {args.render}")
    if args.save:
        bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(args.save))
        print(f"mudcrack_blender: wrote {args.save}")


def _argv():
    return sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []


if __name__ == "__main__":
    try:
        main(_argv())
    except (ShotError, MeshFileError, OSError) as e:
        print(f"mudcrack_blender: error: {e}", file=sys.stderr)
        sys.exit(1)
