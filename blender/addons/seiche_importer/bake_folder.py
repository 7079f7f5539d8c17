# What a Seiche bake folder holds, read without Blender (plain Python): the bake description
# (bake.json: scene name, frame range, the scene text and its --set overrides), the frame rate
# (report.json's effective settings.frame_dt, else the scene's solver.frame_dt after the
# overrides, else the default 1/60 s) and the frame file sequences `<stem>.%04d.<ext>`:
#   particles.%04d.ply        every particle (x y z vx vy vz id)
#   <scene name>.%04d.vdb     the fluid's grids (level set "surface", fog "density", ...)
#   <scene name>.%04d.obj     the fluid surface as a mesh (output.mesh)
#   bodies.%04d.jsonl         every rigid body's transform (a JSON line per body: name, position,
#                             orientation [w, x, y, z], velocity, angular velocity)
#   <body name>.%04d.obj      a rigid body's surface in the world (output.body_meshes): the body's
#                             mesh, not a cloth (the body names are the scene's rigid_bodies)
#   <any other stem>.%04d.obj a mesh whose vertices follow the frames (every cloth)
# Anything wrong raises BakeFolderError with a message naming the file and the problem.
import json
import os
import re

DEFAULT_FRAME_DT = 1.0 / 60.0  # solver.frame_dt's default (docs/scene-format.md)
DEFAULT_SPACING = 0.02  # fluids[k].spacing's default

_FRAME_FILE = re.compile(r"^(?P<stem>[^/]+)\.(?P<frame>\d{4,})\.(?P<ext>vdb|obj|ply|jsonl)$")
_KEY_STEP = re.compile(r"\[(\d+)\]|([^.\[\]]+)")


class BakeFolderError(Exception):
    """A folder or file that is not what a Seiche bake writes; the message says which and why."""


class FrameSequence:
    """The files `<directory>/<stem>.%04d.<ext>` of the frames in `frames` (sorted)."""

    def __init__(self, directory, stem, ext, frames):
        self.directory = directory
        self.stem = stem
        self.ext = ext
        self.frames = sorted(frames)

    def path(self, frame):
        return os.path.join(self.directory, f"{self.stem}.{frame:04d}.{self.ext}")

    @property
    def first(self):
        return self.frames[0]

    @property
    def last(self):
        return self.frames[-1]


class BakeFolder:
    """A bake folder's description and its frame sequences (see the top of this file)."""

    def __init__(self, directory, scene_name, first_frame, last_frame, frame_dt, scene, sequences):
        self.directory = directory
        self.scene_name = scene_name
        self.first_frame = first_frame
        self.last_frame = last_frame
        self.frame_dt = frame_dt
        self.scene = scene  # the scene document with the bake's overrides applied
        by_name = {(s.stem, s.ext): s for s in sequences}
        self.particles = by_name.pop(("particles", "ply"), None)
        self.fluid_vdb = by_name.pop((scene_name, "vdb"), None)
        self.fluid_obj = by_name.pop((scene_name, "obj"), None)
        self.bodies = by_name.pop(("bodies", "jsonl"), None)
        # Every rigid body by name (scene order): its OBJ sequence, or None without body meshes.
        self.body_meshes = {name: by_name.pop((name, "obj"), None) for name in body_names(scene)} \
            if self.bodies else {}
        self.meshes = sorted((s for (stem, ext), s in by_name.items() if ext == "obj"), key=lambda s: s.stem)

    @property
    def frames_present(self):
        """(first, last) over every imported sequence: the frames on disk (an interrupted bake has fewer)."""
        seqs = [s for s in (self.particles, self.fluid_vdb, self.fluid_obj, self.bodies, *self.meshes) if s]
        return min(s.first for s in seqs), max(s.last for s in seqs)

    def fluid_spacing(self):
        """The first fluid's particle spacing (m), or None for a scene without fluid."""
        fluids = self.scene.get("fluids") or []
        if not fluids or not isinstance(fluids[0], dict):
            return None
        spacing = fluids[0].get("spacing", DEFAULT_SPACING)
        return float(spacing) if _is_number(spacing) and spacing > 0 else DEFAULT_SPACING


def body_names(scene):
    """The names of the scene's rigid bodies, in scene order."""
    bodies = scene.get("rigid_bodies") or []
    return [b["name"] for b in bodies if isinstance(b, dict) and isinstance(b.get("name"), str)]


def read_body_frame(path):
    """bodies.%04d.jsonl: {name: (position (3,), orientation [w, x, y, z])}."""
    poses = {}
    try:
        with open(path, "r", encoding="utf-8") as f:
            lines = f.read().splitlines()
    except OSError as e:
        raise BakeFolderError(f"{path}: cannot read: {e.strerror}") from None
    for number, line in enumerate(lines, 1):
        if not line.strip():
            continue
        try:
            body = json.loads(line)
            pose = ([float(v) for v in body["position"]], [float(v) for v in body["orientation"]])
            if len(pose[0]) != 3 or len(pose[1]) != 4:
                raise ValueError("a position of 3 and an orientation of 4 numbers")
            poses[str(body["name"])] = pose
        except (ValueError, KeyError, TypeError) as e:
            raise BakeFolderError(f"{path}: line {number}: not a body's transform ({e})") from None
    return poses


def _is_number(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _read_json(path, what):
    try:
        with open(path, "r", encoding="utf-8") as f:
            return json.load(f)
    except OSError as e:
        raise BakeFolderError(f"{path}: cannot read {what}: {e.strerror}") from None
    except (ValueError, UnicodeDecodeError) as e:
        raise BakeFolderError(f"{path}: damaged {what}: not JSON ({e})") from None


def apply_override(doc, override):
    """One `--set KEY=VALUE` of the bake on the scene document, as Seiche's loader does it:
    KEY is a JSON path (`solver.frame_dt`, `fluids[0].spacing`, `fluids.0.spacing`), VALUE JSON
    or else a plain string. An override that does not fit the document is left out (Seiche
    accepted it when it baked, so it fits the scene the bake read)."""
    key, sep, text = override.partition("=")
    if not sep:
        return
    try:
        value = json.loads(text)
    except ValueError:
        value = text
    steps = [int(index) if index else (int(name) if name.isdigit() else name)
             for index, name in _KEY_STEP.findall(key)]
    node = doc
    for i, step in enumerate(steps):
        last = i + 1 == len(steps)
        if isinstance(step, int):
            if not isinstance(node, list) or step >= len(node):
                return
            if last:
                node[step] = value
            node = node[step]
        else:
            if not isinstance(node, dict):
                return
            if last:
                node[step] = value
            node = node.setdefault(step, {})


def _frame_dt(directory, scene):
    report = os.path.join(directory, "report.json")
    if os.path.isfile(report):
        settings = _read_json(report, "run report").get("settings", {})
        dt = settings.get("frame_dt") if isinstance(settings, dict) else None
        if _is_number(dt) and dt > 0:
            return float(dt)
    solver = scene.get("solver", {})
    dt = solver.get("frame_dt", DEFAULT_FRAME_DT) if isinstance(solver, dict) else DEFAULT_FRAME_DT
    return float(dt) if _is_number(dt) and dt > 0 else DEFAULT_FRAME_DT


def _field(doc, key, kind, path):
    value = doc.get(key) if isinstance(doc, dict) else None
    ok = (_is_number(value) and float(value).is_integer() and value >= 1) if kind is int else isinstance(value, kind)
    if not ok:
        expected = "a whole number >= 1" if kind is int else "a string"
        raise BakeFolderError(f"{path}: damaged bake description: \"{key}\" must be {expected}, got {json.dumps(value)}")
    return int(value) if kind is int else value


def _sequences(directory, first, last):
    frames = {}
    for name in os.listdir(directory):
        m = _FRAME_FILE.match(name)
        if m and first <= int(m["frame"]) <= last:
            frames.setdefault((m["stem"], m["ext"]), []).append(int(m["frame"]))
    return [FrameSequence(directory, stem, ext, f) for (stem, ext), f in frames.items()]


def read_bake_folder(directory):
    """The BakeFolder in `directory` (a folder `seiche bake` wrote), or BakeFolderError."""
    directory = os.path.abspath(directory)
    if not os.path.isdir(directory):
        raise BakeFolderError(f"{directory}: not a folder (pick the folder `seiche bake` wrote)")
    description = os.path.join(directory, "bake.json")
    if not os.path.isfile(description):
        raise BakeFolderError(f"{directory}: not a Seiche bake folder: it has no bake.json "
                              "(`seiche bake SCENE --out DIR` writes one into DIR)")
    doc = _read_json(description, "bake description")
    if not isinstance(doc, dict):
        raise BakeFolderError(f"{description}: damaged bake description: not a JSON object")
    scene_name = _field(doc, "scene_name", str, description)
    first = _field(doc, "first_frame", int, description)
    last = _field(doc, "last_frame", int, description)
    if last < first:
        raise BakeFolderError(f"{description}: damaged bake description: last_frame {last} < first_frame {first}")
    try:
        scene = json.loads(_field(doc, "scene", str, description))
    except ValueError as e:
        raise BakeFolderError(f"{description}: damaged bake description: \"scene\" is not JSON ({e})") from None
    if not isinstance(scene, dict):
        raise BakeFolderError(f"{description}: damaged bake description: \"scene\" is not a JSON object")
    for override in doc.get("overrides") or []:
        if isinstance(override, str):
            apply_override(scene, override)
    bake = BakeFolder(directory, scene_name, first, last, _frame_dt(directory, scene), scene,
                      _sequences(directory, first, last))
    if not (bake.particles or bake.fluid_vdb or bake.fluid_obj or bake.bodies or bake.meshes):
        raise BakeFolderError(f"{directory}: the bake of \"{scene_name}\" (frames {first}-{last}) has no frame "
                              "files yet (particles.%04d.ply, .vdb or .obj): nothing to import")
    return bake
