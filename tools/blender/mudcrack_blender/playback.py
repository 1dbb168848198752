"""Per-frame playback of a mudcrack shot: objects whose mesh follows the scene frame (the
boundary, the cracks and, when the shot wrote debris points, the debris).

Loading strategy: load on frame change, with a small LRU cache bounded in memory.
  * A frame_change_pre handler gives each mudcrack object (custom properties "mudcrack_kind" =
    "boundary", "crack" or "debris", "mudcrack_manifest" = the surface manifest) the mesh of the
    scene's frame, swapping `object.data`. A frame without a crack (debris) file gets an empty
    mesh, never the previous frame's cracks.
  * Pieces: every face of the boundary and crack meshes carries its piece id (the fragment id,
    UV channel 1 of the files) as the integer face attribute "piece", which Geometry Nodes reads
    per frame (Object > Separate mudcrack pieces snapshots one object per piece: pieces.py).
  * Debris is a mesh of vertices only with the point attributes "velocity", "pscale", "id" and
    "piece", ready for Instance on Points; a Geometry Nodes modifier shows the vertices as points
    of radius pscale (debris_points.py).
  * A mesh is built straight from the file (meshfile.py: pure-Python glb/obj reading,
    foreach_set into bpy.data.meshes): no importer, no operator, no objects per frame.
  * Each object keeps the meshes of its recently shown frames, least recently used first out,
    while their estimated size stays within "mudcrack_cache_mb" (a custom property of the
    object, default 512 MB); the mesh on screen is never evicted.
  Why not preload: a shot's meshes grow with its cracks (fig6_eps_0.2's last frame has 6.6 M
  crack triangles, several GB for all of its frames), so loading every frame up front costs the
  whole shot's memory and a long wait before the first frame shows. On frame change only what is
  shown is loaded: the demo's last frame takes 0.26 s for the boundary (39 K vertices, 72 K
  triangles) and 0.60 s for the cracks (150 K triangles) in Debian's Blender 3.4 on a loaded
  2-core machine, most of it in Blender's own calls (custom normals, edges); a frame seen
  before comes from the cache.
  Evicted meshes are removed from bpy.data; cached meshes have no users, so a saved .blend holds
  only the frame on screen and reloading a file starts with an empty cache (load_post).

Handlers are @persistent (they survive File > Open and File > Revert) and registered once: any
handler of the same name (an earlier registration, e.g. the add-on and the CLI script in the same
session) is removed before adding ours.

Blender API notes (3.4 and 4.x): `MeshPolygon.loop_total` is written only before 4.0 (read-only
there, faces are defined by loop_start); `Mesh.use_auto_smooth` is set for custom normals only
where it exists (removed in 4.1, where custom normals need no flag); color attributes use
`Mesh.color_attributes` (3.2+), never the deprecated `vertex_colors`.
"""
from array import array
from collections import OrderedDict
from itertools import chain
import math
import os
import sys

import bpy
from bpy.app.handlers import persistent

from .debris_points import add_debris_points_modifier
from .debrisfile import read_debris_ply
from .materials import COLOR_ATTRIBUTE, material_for
from .meshfile import MeshFileError, read_mesh_file
from .shot import DEBRIS, KINDS, ShotError, SurfaceShot, load_surface_shot

__all__ = ["PROP_KIND", "PROP_MANIFEST", "PROP_CACHE_MB", "register_handlers", "unregister_handlers",
           "update_scene", "import_shot", "clear_caches", "cached_mesh_names", "surface_shot"]

PROP_KIND = "mudcrack_kind"          # object: "boundary" or "crack"
PROP_MANIFEST = "mudcrack_manifest"  # object: absolute path of surface/manifest.json
PROP_CACHE_MB = "mudcrack_cache_mb"  # object: cache budget [MB]
PROP_FILE = "mudcrack_file"          # mesh: the file it was built from ("" for the empty mesh)
DEFAULT_CACHE_MB = 512.0
UV_TEXTURE = "UVMap"                 # UV channel 0, for texturing
UV_FRAGMENT = "fragment"             # UV channel 1: (fragment id, 0)
PIECE_ATTRIBUTE = "piece"            # int per face (meshes) or per point (debris): the piece id

_shots = {}     # manifest path -> (mtime, SurfaceShot)
_caches = {}    # (object name, manifest, kind) -> OrderedDict(file -> (mesh name, estimated bytes))
_reported = set()


def _log(message):
    print(f"mudcrack_blender: {message}", file=sys.stderr)


def clear_caches():
    """Forgets every cached frame (the meshes stay in bpy.data until unused)."""
    _shots.clear()
    _caches.clear()


def surface_shot(manifest):
    """The SurfaceShot of a manifest path, re-read when the file changed (a re-run of the surfacing)."""
    mtime = os.stat(manifest).st_mtime_ns
    hit = _shots.get(manifest)
    if hit is None or hit[0] != mtime:
        hit = (mtime, SurfaceShot(manifest))
        _shots[manifest] = hit
    return hit[1]


def _estimated_bytes(mesh):
    """Blender's memory for a triangle mesh, roughly: 60 bytes per vertex and 150 per triangle
    (its corners, edges, UVs and custom normals), calibrated on the demo's meshes in Blender 3.4
    (process RSS after building 10 frames: 14 MB per boundary frame of 39 K vertices and 72 K
    triangles, 27 MB per crack frame of about 140 K vertices and triangles)."""
    return 60 * len(mesh.vertices) + 150 * len(mesh.polygons)


def empty_mesh():
    """The shared mesh with no vertices: frames without cracks show it."""
    for me in bpy.data.meshes:
        if me.get(PROP_FILE) == "" and len(me.vertices) == 0:
            return me
    me = bpy.data.meshes.new("mudcrack empty")
    me[PROP_FILE] = ""
    return me


def face_pieces(data):
    """The piece id of each triangle of MeshData, from its first corner's UV channel 1 (the
    writer gives every vertex of a piece that piece's (id, 0); ids below 2^24 are exact in
    float), or None when the file has no channel 1 (obj)."""
    if data.uv1 is None:
        return None
    u = data.uv1[0::2]
    return array("i", map(int, map(u.__getitem__, data.indices[0::3])))  # C loops: no per-face Python


def add_attribute(me, name, kind, domain, values):
    """A generic mesh attribute filled from a flat array ("value" or "vector" per element)."""
    attr = me.attributes.new(name, kind, domain)
    attr.data.foreach_set("vector" if kind == "FLOAT_VECTOR" else "value", values)
    return attr


def build_mesh(name, data, kind):
    """A bpy mesh of MeshData: triangles, smooth with the file's normals, UV channel 0
    ("UVMap"), the fragment ids ("fragment", UV channel 1, and per face as the int attribute
    "piece"), COLOR_0 as the color attribute "Col" and the kind's material."""
    me = bpy.data.meshes.new(name)
    n, m = data.vertex_count, data.face_count
    me.vertices.add(n)
    me.vertices.foreach_set("co", data.positions)
    indices = array("i")
    indices.frombytes(data.indices.tobytes())  # same bits: every index is < n < 2^31
    me.loops.add(3 * m)
    me.loops.foreach_set("vertex_index", indices)
    me.polygons.add(m)
    me.polygons.foreach_set("loop_start", array("i", range(0, 3 * m, 3)))
    if bpy.app.version < (4, 0, 0):
        me.polygons.foreach_set("loop_total", array("i", [3]) * m)
    for layer_name, uv in ((UV_TEXTURE, data.uv0), (UV_FRAGMENT, data.uv1)):
        if uv is None:
            continue
        layer = me.uv_layers.new(name=layer_name)
        pairs = list(zip(uv[0::2], uv[1::2]))
        layer.data.foreach_set("uv", array("f", chain.from_iterable(map(pairs.__getitem__, indices))))
    if me.uv_layers:
        me.uv_layers.active = me.uv_layers[0]
        me.uv_layers[0].active_render = True
    if data.colors is not None:
        colors = me.color_attributes.new(COLOR_ATTRIBUTE, "FLOAT_COLOR", "POINT")
        colors.data.foreach_set("color", data.colors)
        me.color_attributes.active_color = colors
    me.update(calc_edges=True)
    pieces = face_pieces(data)
    if pieces is not None:
        add_attribute(me, PIECE_ATTRIBUTE, "INT", "FACE", pieces)
    me.polygons.foreach_set("use_smooth", array("b", [1]) * m)
    if data.normals is not None and n:
        if hasattr(me, "use_auto_smooth"):
            me.use_auto_smooth = True
            me.auto_smooth_angle = math.pi
        nrm = data.normals
        me.normals_split_custom_set_from_vertices(list(zip(nrm[0::3], nrm[1::3], nrm[2::3])))
    me.materials.append(material_for(kind))
    me.update()
    return me


def build_debris_mesh(name, debris):
    """A bpy mesh of DebrisData: one vertex per grain, no edges or faces, with the point
    attributes "velocity" (m/s, y-up like the positions: the shot's root turns both), "pscale"
    (radius, m), "id" (the same grain in every frame: Geometry Nodes' random values follow it)
    and "piece" (the piece it tore from, or -1): the names Houdini's File SOP gives them too,
    except "velocity", Blender's name for Houdini's "v"."""
    me = bpy.data.meshes.new(name)
    me.vertices.add(debris.point_count)
    me.vertices.foreach_set("co", debris.positions)
    add_attribute(me, "velocity", "FLOAT_VECTOR", "POINT", debris.velocities)
    add_attribute(me, "pscale", "FLOAT", "POINT", debris.pscale)
    add_attribute(me, "id", "INT", "POINT", debris.ids)
    add_attribute(me, PIECE_ATTRIBUTE, "INT", "POINT", debris.pieces)
    me.update()
    return me


def _estimated_debris_bytes(me):
    """Blender's memory for a debris mesh, roughly: a vertex and 24 bytes of attributes a point."""
    return 90 * len(me.vertices)


def _build_for(kind, path, name):
    """The mesh of a shot's file: a debris point file or a boundary/crack mesh file."""
    if kind == DEBRIS:
        me = build_debris_mesh(name, read_debris_ply(path))
        return me, _estimated_debris_bytes(me)
    me = build_mesh(name, read_mesh_file(path), kind)
    return me, _estimated_bytes(me)


def _cache_budget(obj):
    try:
        return max(0.0, float(obj.get(PROP_CACHE_MB, DEFAULT_CACHE_MB))) * 1e6
    except (TypeError, ValueError):
        return DEFAULT_CACHE_MB * 1e6


def _mesh_for(obj, shot, frame):
    """The mesh object `obj` shows at `frame`, from its cache or loaded now."""
    kind = obj[PROP_KIND]
    path = shot.file(kind, frame)
    if path is None:
        return empty_mesh()
    cache = _caches.setdefault((obj.name, shot.manifest_path, kind), OrderedDict())
    hit = cache.get(path)
    if hit is not None:
        me = bpy.data.meshes.get(hit[0])
        if me is not None and me.get(PROP_FILE) == path:
            cache.move_to_end(path)
            return me
        del cache[path]  # removed behind our back (orphans purged, undo)
    shot.verify(path)
    me, size = _build_for(kind, path, f"{shot.name} {kind}.{min(max(frame, shot.first), shot.last):04d}")
    me[PROP_FILE] = path
    cache[path] = (me.name, size)
    return me


def _evict(obj):
    """Drops the object's least recently used meshes beyond its budget (after the swap, so the
    mesh shown before is unused now and can go); the mesh on screen, the newest, always stays."""
    budget = _cache_budget(obj)
    for key, cache in _caches.items():
        if key[0] != obj.name:
            continue
        while len(cache) > 1 and sum(size for _, size in cache.values()) > budget:
            _, (name, _) = cache.popitem(last=False)
            old = bpy.data.meshes.get(name)
            if old is not None and old.users == 0:
                bpy.data.meshes.remove(old)


def update_object(obj, frame):
    """Gives a mudcrack object its mesh of `frame`. A file that cannot be read shows an empty
    mesh and is reported once on stderr (a handler must not raise)."""
    manifest = obj.get(PROP_MANIFEST)
    if obj.get(PROP_KIND) not in KINDS + (DEBRIS,) or not manifest:
        return
    try:
        me = _mesh_for(obj, surface_shot(bpy.path.abspath(manifest)), frame)
    except (OSError, ShotError, MeshFileError) as e:
        message = str(e) if not isinstance(e, OSError) else f"{manifest}: {e.strerror}"
        if message not in _reported:
            _reported.add(message)
            _log(f"{obj.name}, frame {frame}: {message} (showing an empty mesh)")
        me = empty_mesh()
    if obj.data is not me:
        obj.data = me
    _evict(obj)


def update_scene(scene):
    """Every mudcrack object of the scene shows the scene's current frame."""
    frame = scene.frame_current
    for obj in scene.objects:
        if obj.type == "MESH" and PROP_KIND in obj:
            update_object(obj, frame)


@persistent
def mudcrack_frame_change(scene, *args):
    update_scene(scene)


@persistent
def mudcrack_load_post(*args):
    # the cache's mesh names belong to the file that was open
    clear_caches()
    _reported.clear()


_HANDLERS = (("frame_change_pre", mudcrack_frame_change), ("load_post", mudcrack_load_post))


def register_handlers():
    """Adds the handlers once: handlers of the same names are removed first."""
    unregister_handlers()
    for list_name, fn in _HANDLERS:
        getattr(bpy.app.handlers, list_name).append(fn)


def unregister_handlers():
    for list_name, fn in _HANDLERS:
        handlers = getattr(bpy.app.handlers, list_name)
        for h in [h for h in handlers if getattr(h, "__name__", None) == fn.__name__]:
            handlers.remove(h)


def cached_mesh_names(obj):
    """Names of the meshes cached for `obj` (least recently used first); for tests and the UI."""
    names = []
    for (name, _manifest, _kind), cache in _caches.items():
        if name == obj.name:
            names.extend(n for n, _ in cache.values())
    return names


def check_frame_files(shot, frame):
    """Raises ShotError when a mesh or debris file of `frame` is damaged: an import or a CLI run
    refuses it with that message instead of showing an empty mesh as playback does."""
    for kind in KINDS + (DEBRIS,):
        path = shot.file(kind, frame)
        if path is not None:
            shot.verify(path)


def import_shot(context, path, cache_mb=DEFAULT_CACHE_MB):
    """Imports a shot's surfacing output (a shot folder, its surface/ folder or manifest.json):
    one object "<shot> boundary" and one "<shot> crack" (and "<shot> debris" when the shot wrote
    debris points; a shot without them gets none), children of an empty "<shot>" that turns
    mudcrack's y-up into Blender's z-up (a +90 degree rotation about x: the only conversion), in
    a new collection "mudcrack <shot>". Sets the scene's frame range and fps from the manifest
    and shows the first frame. Returns (root, {kind: object}). Raises ShotError, also when that
    frame's files are damaged."""
    shot = load_surface_shot(path)
    scene = context.scene
    check_frame_files(shot, scene.frame_current)
    # a shot cached before must be read again (same path, maybe new files)
    _shots.pop(shot.manifest_path, None)
    register_handlers()

    scene.frame_start, scene.frame_end = shot.first, shot.last
    fps = max(1, round(shot.fps))
    scene.render.fps = fps
    scene.render.fps_base = fps / shot.fps
    # the handler swaps meshes while a render runs: keep the UI from touching them meanwhile
    scene.render.use_lock_interface = True

    collection = bpy.data.collections.new(f"mudcrack {shot.name}")
    scene.collection.children.link(collection)
    root = bpy.data.objects.new(shot.name, None)
    root.empty_display_type = "PLAIN_AXES"
    root.rotation_euler = (math.pi / 2, 0.0, 0.0)  # y-up -> z-up: (x, y, z) -> (x, -z, y)
    root["mudcrack_shot"] = shot.manifest_path
    collection.objects.link(root)
    objects = {}
    for kind in KINDS + ((DEBRIS,) if shot.has_debris else ()):
        obj = bpy.data.objects.new(f"{shot.name} {kind}", empty_mesh())
        obj.parent = root
        obj[PROP_KIND] = kind
        obj[PROP_MANIFEST] = shot.manifest_path
        obj[PROP_CACHE_MB] = float(cache_mb)
        if kind == DEBRIS:
            add_debris_points_modifier(obj)
        collection.objects.link(obj)
        objects[kind] = obj
    frame = min(max(scene.frame_current, shot.first), shot.last)
    scene.frame_set(frame)
    return root, objects
