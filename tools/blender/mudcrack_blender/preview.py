"""A look-development stage around an imported shot, for stills (cli.py --render): the camera
mc-render uses, a sun, a sky and a grey ground, rendered with Cycles on the CPU.

The camera is mc-render's camera for the shot's frames: /render/camera from the render slice
make writes (out/<shot>/render.params.json) when the shot fixes one; otherwise mc-render's
automatic framing (render/camera.cpp auto_frame: from 35 degrees azimuth, 26 degrees above, the
bounds of every frame filling 88 % of the frame, /render/camera/fov of 35 degrees), so a still
matches mc-render's frame.####.png of the same frame.
"""
import json
import math
import os

import bpy
from mathutils import Vector

from .meshfile import read_mesh_file
from .shot import KINDS

__all__ = ["stage_for_still", "render_still"]

_AZIMUTH, _ELEVATION, _FILL, _FOV = math.radians(35.0), math.radians(26.0), 0.88, 35.0


def _to_blender(p):
    """mudcrack's y-up coordinates -> Blender's z-up (the rotation the shot's root applies)."""
    return Vector((p[0], -p[2], p[1]))


def _stage_bounds(shot):
    """Bounds of every frame's meshes, in mudcrack coordinates (mc-render's stage_bounds)."""
    lo, hi = [math.inf] * 3, [-math.inf] * 3
    for frame in range(shot.first, shot.last + 1):
        for kind in KINDS:
            path = shot.files[frame][kind]
            if path is None:
                continue
            p = read_mesh_file(path).positions
            for k in range(3):
                if len(p):
                    lo[k], hi[k] = min(lo[k], min(p[k::3])), max(hi[k], max(p[k::3]))
    if lo[0] > hi[0]:
        lo, hi = [0.0] * 3, [0.0] * 3
    return lo, hi


def _auto_camera(lo, hi, aspect, fov_deg):
    """render/camera.cpp auto_frame, in mudcrack coordinates: (eye, target)."""
    c = [(a + b) / 2 for a, b in zip(lo, hi)]
    back = (math.sin(_AZIMUTH) * math.cos(_ELEVATION), math.sin(_ELEVATION), math.cos(_AZIMUTH) * math.cos(_ELEVATION))
    f = Vector(back) * -1
    s = f.cross(Vector((0, 1, 0))).normalized()
    u = s.cross(f)
    tan_v = math.tan(math.radians(fov_deg) / 2) * _FILL
    tan_h = tan_v * aspect
    d = 0.0
    for i in range(8):
        p = Vector((hi[0] if i & 1 else lo[0], hi[1] if i & 2 else lo[1], hi[2] if i & 4 else lo[2]))
        q = p - Vector(c)
        x, y, z = q.dot(s), q.dot(u), -q.dot(f)
        d = max(d, z + abs(x) / tan_h, z + abs(y) / tan_v)
    d = max(d, 1e-3)
    return [ci + bi * d for ci, bi in zip(c, back)], c


def _render_slice_camera(shot):
    """/render/camera of the render slice next to the shot's stages: (camera dict or None, fov)."""
    path = os.path.join(os.path.dirname(shot.surface_dir), "render.params.json")
    try:
        with open(path, "r", encoding="utf-8") as f:
            render = json.load(f).get("render", {})
    except (OSError, ValueError):
        return None, _FOV
    camera = render.get("camera")
    if isinstance(camera, dict) and "position" in camera and "target" in camera:
        return camera, float(camera.get("fov", _FOV))
    return None, _FOV


def stage_for_still(scene, shot, objects, width, height, samples, threads):
    """Adds mc-render's camera, a sun, a sky and a ground to `scene` and sets Cycles (CPU) up."""
    camera, fov = _render_slice_camera(shot)
    if camera is not None:
        eye, target = camera["position"], camera["target"]
    else:
        eye, target = _auto_camera(*_stage_bounds(shot), width / height, fov)
    cam_data = bpy.data.cameras.new("mudcrack camera")
    cam_data.sensor_fit = "VERTICAL"
    cam_data.angle_y = math.radians(fov)
    cam_data.clip_start, cam_data.clip_end = 0.01, 1000.0
    cam = bpy.data.objects.new("mudcrack camera", cam_data)
    eye_b, target_b = _to_blender(eye), _to_blender(target)
    cam.location = eye_b
    cam.rotation_euler = (target_b - eye_b).to_track_quat("-Z", "Y").to_euler()
    scene.collection.objects.link(cam)
    scene.camera = cam

    # a key sun from the camera's upper left, soft shadows
    sun_data = bpy.data.lights.new("mudcrack sun", "SUN")
    sun_data.energy = 3.5
    sun_data.angle = math.radians(8.0)
    sun = bpy.data.objects.new("mudcrack sun", sun_data)
    view = (target_b - eye_b).normalized()
    left = view.cross(Vector((0, 0, 1))).normalized() * -1
    to_light = (Vector((0, 0, 1)) * 1.6 + left * 0.8 - view * 0.5).normalized()
    sun.rotation_euler = (-to_light).to_track_quat("-Z", "Y").to_euler()
    scene.collection.objects.link(sun)

    # sky: mc-render's sky color (linear)
    world = bpy.data.worlds.new("mudcrack sky")
    world.use_nodes = True
    background = world.node_tree.nodes.get("Background")
    background.inputs["Color"].default_value = (0.26, 0.29, 0.34, 1.0)
    background.inputs["Strength"].default_value = 1.0
    scene.world = world

    # ground: mudcrack's y = 0 plane (Blender z = 0), mc-render's neutral grey
    size = 50.0
    ground_mesh = bpy.data.meshes.new("mudcrack ground")
    ground_mesh.from_pydata([(-size, -size, 0), (size, -size, 0), (size, size, 0), (-size, size, 0)], [], [(0, 1, 2, 3)])
    ground_mat = bpy.data.materials.new("mudcrack ground")
    ground_mat.use_nodes = True
    bsdf = ground_mat.node_tree.nodes.get("Principled BSDF")
    bsdf.inputs["Base Color"].default_value = (0.16, 0.16, 0.16, 1.0)
    bsdf.inputs["Roughness"].default_value = 0.8
    ground_mesh.materials.append(ground_mat)
    ground = bpy.data.objects.new("mudcrack ground", ground_mesh)
    scene.collection.objects.link(ground)

    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    # Debian's Cycles is built without OpenImageDenoise
    scene.cycles.use_denoising = False
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.render.resolution_percentage = 100
    # Filmic with more contrast: closer to mc-render's ACES-like curve (the look's name differs
    # between builds: Debian's 3.4 "Medium High Contrast", upstream's "Filmic - Medium High
    # Contrast"; 4.x's AgX looks are named otherwise: then the default look stays)
    scene.view_settings.view_transform = "Filmic"
    for look in ("Medium High Contrast", "Filmic - Medium High Contrast"):
        try:
            scene.view_settings.look = look
            break
        except TypeError:
            continue
    scene.render.image_settings.file_format = "PNG"
    scene.render.image_settings.color_mode = "RGB"
    if threads > 0:
        scene.render.threads_mode = "FIXED"
        scene.render.threads = threads


def render_still(scene, path):
    """Renders the current frame to `path` (PNG)."""
    scene.render.filepath = os.path.abspath(path)
    bpy.ops.render.render(write_still=True)
