"""A mudcrack shot's surfacing output as the add-on sees it: surface/manifest.json, read once.
Pure Python (no bpy), so it is usable outside Blender too.

The manifest (written by mc-surface, or by the farm's merge) lists every frame with its boundary
file and its crack file; a frame without an open crack has "crack": {"file": null} and no crack
file on disk, and the add-on shows an empty crack mesh then. In the plates mode with
"debris": "points" each frame also lists its debris point file ("debris": {"file": ...}); a
shot without debris lists none, and the add-on makes no debris object for it. Each file's record
holds its CRC-32 ("crc32"), and a file is verified against it before it is shown.
"""
import json
import os
import zlib

from .meshfile import SUPPORTED_EXTENSIONS

__all__ = ["ShotError", "SurfaceShot", "file_crc32", "locate_manifest", "load_surface_shot", "KINDS", "DEBRIS"]

KINDS = ("boundary", "crack")  # the mesh files of a frame
DEBRIS = "debris"              # the point file of a frame (plates mode, "debris": "points")


class ShotError(Exception):
    """A shot folder or manifest the add-on cannot use; the message says which file and why."""


def locate_manifest(path):
    """The surface manifest for what a user picked: a shot's output folder (OUT/<shot>), its
    surface/ folder, the manifest itself, or any file inside surface/ (e.g. boundary.0001.glb)."""
    path = os.path.abspath(os.path.expanduser(path))
    if os.path.isdir(path):
        for candidate in (os.path.join(path, "surface", "manifest.json"), os.path.join(path, "manifest.json")):
            if os.path.isfile(candidate):
                return candidate
        raise ShotError(f"{path}: neither {os.path.join('surface', 'manifest.json')} nor manifest.json here: "
                        "pick a shot's output folder (out/<shot>) after its surfacing stage has run "
                        "(make shot SHOT=<shot>)")
    if not os.path.exists(path):
        raise ShotError(f"{path}: no such file or folder")
    if os.path.basename(path) == "manifest.json":
        return path
    candidate = os.path.join(os.path.dirname(path), "manifest.json")
    if os.path.isfile(candidate):
        return candidate
    raise ShotError(f"{path}: not a mudcrack surface manifest, and no manifest.json next to it")


class SurfaceShot:
    """What the add-on needs from surface/manifest.json.

    name: the shot (the output folder's name); surface_dir: absolute; first, last: frame range;
    fps: frames per second; format: mesh file extension; files[frame] = {"boundary": path or None,
    "crack": path or None, "debris": path or None} (absolute paths; None: the frame has no such
    file); has_debris: some frame has a debris file.
    """

    def __init__(self, manifest_path):
        self.manifest_path = os.path.abspath(manifest_path)
        self.surface_dir = os.path.dirname(self.manifest_path)
        self.name = os.path.basename(os.path.dirname(self.surface_dir)) or "mudcrack"
        where = self.manifest_path
        try:
            with open(self.manifest_path, "r", encoding="utf-8") as f:
                m = json.load(f)
        except OSError as e:
            raise ShotError(f"{where}: cannot read: {e.strerror}") from None
        except ValueError as e:
            raise ShotError(f"{where}: not valid JSON: {e}") from None
        if not isinstance(m, dict) or m.get("stage") != "surface":
            stage = m.get("stage") if isinstance(m, dict) else None
            raise ShotError(f"{where}: /stage = {json.dumps(stage)}: expected \"surface\" (the manifest of "
                            "mc-surface's output folder, out/<shot>/surface/manifest.json)")
        frames = m.get("frames", {})
        try:
            self.first, self.last = int(frames["first"]), int(frames["last"])
        except (KeyError, TypeError, ValueError):
            raise ShotError(f"{where}: /frames/first and /frames/last: missing or not integers") from None
        if self.last < self.first:
            raise ShotError(f"{where}: /frames: last {self.last} < first {self.first}")
        self.fps = self._fps(frames)
        self.format = str(m.get("format", "glb")).lower()
        ext = "." + self.format
        if ext not in SUPPORTED_EXTENSIONS:
            raise ShotError(f"{where}: /format = \"{self.format}\": the mudcrack add-on reads "
                            f"{' and '.join(e[1:] for e in SUPPORTED_EXTENSIONS)} meshes; re-run the surfacing "
                            "with \"surfacing\": {\"format\": \"glb\"} (the default)")
        self.files = {}
        self.crc32 = {}  # path -> the CRC-32 mc-surface recorded for it
        per_frame = m.get("per_frame")
        if not isinstance(per_frame, list):
            raise ShotError(f"{where}: /per_frame: missing or not a list")
        for i, entry in enumerate(per_frame):
            try:
                n = int(entry["frame"])
                boundary = entry["boundary"]["file"]
            except (KeyError, TypeError, ValueError):
                raise ShotError(f"{where}: /per_frame/{i}: no frame number or boundary file") from None
            crack = (entry.get("crack") or {}).get("file")
            debris = (entry.get("debris") or {}).get("file")
            self.files[n] = {kind: (os.path.join(self.surface_dir, f) if f else None)
                             for kind, f in (("boundary", boundary), ("crack", crack), (DEBRIS, debris))}
            for kind in KINDS + (DEBRIS,):
                record = entry.get(kind)
                if self.files[n][kind] and isinstance(record, dict) and isinstance(record.get("crc32"), str):
                    self.crc32[self.files[n][kind]] = record["crc32"]
        missing = [n for n in range(self.first, self.last + 1) if n not in self.files]
        if missing:
            raise ShotError(f"{where}: /per_frame: no entry for frame(s) {_ranges(missing)} of "
                            f"{self.first}-{self.last} (an interrupted surfacing run? re-run make shot)")
        self.has_debris = any(files[DEBRIS] for files in self.files.values())

    def _fps(self, frames):
        """/frames/fps; manifests written before it was recorded: the sim manifest's."""
        fps = frames.get("fps")
        source = self.manifest_path + ": /frames/fps"
        if fps is None:
            sim_manifest = os.path.join(os.path.dirname(self.surface_dir), "sim", "manifest.json")
            try:
                with open(sim_manifest, "r", encoding="utf-8") as f:
                    fps = json.load(f).get("frames", {}).get("fps")
                source = sim_manifest + ": /frames/fps"
            except (OSError, ValueError):
                fps = None
            if fps is None:
                raise ShotError(f"{self.manifest_path}: no /frames/fps, and no readable {sim_manifest} that has "
                                "it: re-run the surfacing with this version of mc-surface")
        try:
            fps = float(fps)
        except (TypeError, ValueError):
            fps = -1.0
        if not fps > 0:
            raise ShotError(f"{source} = {frames.get('fps')}: expected a number > 0")
        return fps

    def verify(self, path):
        """Raises ShotError unless the file at `path` holds the bytes whose checksum mc-surface
        recorded in the manifest: a damaged file (or one no checksum vouches for) is never shown."""
        recorded = self.crc32.get(path)
        if recorded is None:
            raise ShotError(f"{path}: no checksum recorded for it in {self.manifest_path}, so it cannot be "
                            "verified: re-run mc-surface")
        found = file_crc32(path)
        if found != recorded:
            raise ShotError(f"{path}: damaged: its CRC-32 is {found}, but {self.manifest_path} records "
                            f"{recorded}: re-run mc-surface")

    def file(self, kind, frame):
        """The file of `kind` (KINDS or DEBRIS) shown at scene frame `frame`, or None for an empty mesh.
        Outside the shot's range the nearest end frame holds (a cache's usual behaviour)."""
        frame = min(max(int(frame), self.first), self.last)
        return self.files[frame][kind]


def file_crc32(path):
    """The CRC-32 of a file's bytes as mc-surface records it (zlib's, 8 lowercase hex digits)."""
    crc = 0
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            crc = zlib.crc32(block, crc)
    return f"{crc & 0xffffffff:08x}"


def _ranges(numbers):
    out, start = [], None
    for i, n in enumerate(numbers):
        if start is None:
            start = n
        if i + 1 == len(numbers) or numbers[i + 1] != n + 1:
            out.append(str(start) if start == n else f"{start}-{n}")
            start = None
    return ", ".join(out)


def load_surface_shot(path):
    """The shot of `path` (see locate_manifest). Raises ShotError."""
    return SurfaceShot(locate_manifest(path))
