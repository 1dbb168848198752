"""mudcrack shot importer for Blender: a shot's per-frame surfacing meshes
(out/<shot>/surface/boundary.####.glb, crack.####.glb, manifest.json) play back as ONE animated
soil object and ONE animated crack object, and its debris points (debris.####.ply, when the
plates mode wrote them) as one animated point object. Every face carries its piece id (the int
face attribute "piece"); Object > Separate mudcrack pieces makes one object per piece of the
frame on screen (pieces.py).

Install: `make blender-addon` writes build/mudcrack_blender.zip; Blender > Edit > Preferences >
Add-ons > Install... > that zip, then tick "Import-Export: mudcrack shot". Import with File >
Import > mudcrack shot (pick out/<shot>, its surface/ folder or surface/manifest.json).
Without installing: `blender --python tools/blender/mudcrack_blender/cli.py -- out/<shot>`
(cli.py documents its options).

playback.py explains the loading strategy (on frame change, LRU cache bounded in memory);
meshfile.py and debrisfile.py the file reading (pure Python, no glTF importer: Debian's Blender
3.4 has no numpy);
materials.py the shaders. Written for Blender 3.4 (Debian 12) against API that 4.x keeps; where
the two differ the code says so (playback.py).
"""

bl_info = {
    "name": "mudcrack shot",
    "author": "mudcrack",
    "version": (1, 0, 0),
    "blender": (3, 4, 0),
    "location": "File > Import > mudcrack shot",
    "description": "Plays a mudcrack shot's per-frame boundary and crack meshes and debris points as animated objects",
    "category": "Import-Export",
}

if "bpy" in locals():  # F8 / script reload: pick up edited submodules
    import importlib

    for _m in ("meshfile", "debrisfile", "shot", "materials", "debris_points", "playback", "pieces"):
        if _m in locals():
            importlib.reload(locals()[_m])

import os

import bpy
from bpy.props import FloatProperty, StringProperty
from bpy_extras.io_utils import ImportHelper

from . import debris_points, debrisfile, materials, meshfile, pieces, playback, shot  # noqa: F401 (reloaded above)
from .meshfile import MeshFileError
from .shot import KINDS, ShotError


class MUDCRACK_OT_import_shot(bpy.types.Operator, ImportHelper):
    """Import a mudcrack shot: one soil and one crack object whose meshes follow the frame"""

    bl_idname = "import_scene.mudcrack_shot"
    bl_label = "Import mudcrack shot"
    bl_options = {"REGISTER", "UNDO", "PRESET"}

    filename_ext = ".json"
    filter_glob: StringProperty(default="manifest.json;*.glb;*.obj", options={"HIDDEN"})
    cache_mb: FloatProperty(
        name="Cache (MB)",
        description="Memory for recently shown frames per object (least recently used frames are dropped)",
        default=playback.DEFAULT_CACHE_MB, min=0.0, soft_max=8192.0)

    def execute(self, context):
        path = self.filepath
        # the file browser gives "<folder>/" when a folder is picked with no file
        if not os.path.exists(path) and os.path.isdir(os.path.dirname(path)):
            path = os.path.dirname(path)
        try:
            root, objects = playback.import_shot(context, path, self.cache_mb)
        except (ShotError, MeshFileError, OSError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        for obj in context.view_layer.objects:
            obj.select_set(False)
        for obj in objects.values():
            obj.select_set(True)
        context.view_layer.objects.active = objects["boundary"]
        scene = context.scene
        self.report({"INFO"}, f"mudcrack: {root.name}: frames {scene.frame_start}-{scene.frame_end} "
                              f"at {scene.render.fps / scene.render.fps_base:g} fps")
        return {"FINISHED"}


def shot_objects_of(obj):
    """{kind: object} of the playback objects of the shot that `obj` (one of them, or their root)
    belongs to; {} for other objects."""
    root = obj.parent if obj is not None and obj.get(playback.PROP_KIND) else obj
    if root is None or "mudcrack_shot" not in root:
        return {}
    return {child[playback.PROP_KIND]: child for child in root.children if child.get(playback.PROP_KIND) in KINDS}


class MUDCRACK_OT_separate_pieces(bpy.types.Operator):
    """One object per piece of the frame on screen (piece_<id>, its soil faces and crack walls),
    from the active mudcrack shot; the playback objects stay as they are"""

    bl_idname = "object.mudcrack_separate_pieces"
    bl_label = "Separate mudcrack pieces"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return bool(shot_objects_of(context.active_object))

    def execute(self, context):
        objects = shot_objects_of(context.active_object)
        frame = context.scene.frame_current
        try:
            collection, made = pieces.separate_pieces(context, objects, frame)
        except (MeshFileError, OSError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        if not made:
            self.report({"WARNING"}, f"frame {frame}: the meshes carry no piece ids (an obj surfacing?)")
            return {"CANCELLED"}
        for obj in context.view_layer.objects:
            obj.select_set(False)
        for obj in made:
            obj.select_set(True)
        context.view_layer.objects.active = made[0]
        self.report({"INFO"}, f"mudcrack: {len(made)} pieces of frame {frame} in '{collection.name}'")
        return {"FINISHED"}


def _menu_import(self, context):
    self.layout.operator(MUDCRACK_OT_import_shot.bl_idname, text="mudcrack shot (manifest.json)")


def _menu_object(self, context):
    self.layout.operator(MUDCRACK_OT_separate_pieces.bl_idname)


_classes = (MUDCRACK_OT_import_shot, MUDCRACK_OT_separate_pieces)


def register():
    """Registers the operator, its File > Import entry and the playback handlers (once)."""
    for cls in _classes:
        if not cls.is_registered:
            bpy.utils.register_class(cls)
    bpy.types.TOPBAR_MT_file_import.remove(_menu_import)
    bpy.types.TOPBAR_MT_file_import.append(_menu_import)
    bpy.types.VIEW3D_MT_object.remove(_menu_object)
    bpy.types.VIEW3D_MT_object.append(_menu_object)
    playback.register_handlers()


def unregister():
    playback.unregister_handlers()
    bpy.types.TOPBAR_MT_file_import.remove(_menu_import)
    bpy.types.VIEW3D_MT_object.remove(_menu_object)
    for cls in reversed(_classes):
        if cls.is_registered:
            bpy.utils.unregister_class(cls)
    playback.clear_caches()
