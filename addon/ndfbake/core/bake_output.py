"""What a bake wrote, as the library hands it back (ndfb_bake_result): the levels and their sizes,
the lobe slots and which of them hold lobes, the atlas layout and every file by kind, level and
slot. The add-on reads the bake from this, never by listing its folder or parsing report.json.
No bpy; read() is native.Context.bake's."""
import ctypes
from dataclasses import dataclass, field

from .native_abi import FILE_ATLAS, FILE_LOBE, AtlasFrame, BakeFile


@dataclass(frozen=True)
class WrittenFile:
    kind: int          # native_abi.FILE_*
    level: int         # -1: not one level's (atlas, MIP-mapped, shader, report)
    slot: int          # -1: not one slot's
    name: str          # in the bake's folder


@dataclass
class BakeOutput:
    levels: list                     # (width, height) per level, level 0 first
    slots: int                       # lobe slots per level: the fit's maximum lobes
    slots_used: list                 # per slot: does any texel of any level hold a lobe in it
    atlas_size: tuple = (0, 0)       # (width, height) of the atlas files; (0, 0): none written
    atlas_frames: list = field(default_factory=list)  # per level {"x", "y", "width", "height"}
    files: list = field(default_factory=list)         # WrittenFile, report.json last

    def used_slot_files(self, kind, level=-1):
        """{slot: name} of the files of `kind` (native_abi.FILE_*) at `level` (-1: of every level), for
        the slots that hold lobes: one no texel uses (a tolerance left it empty) is all zero."""
        return {f.slot: f.name for f in self.files if f.kind == kind and f.level == level and self.slots_used[f.slot]}

    def lobe_textures(self, atlas):
        """{slot: name} of what a node group samples, used slots only: the atlas files, or level 0's
        lobe files."""
        return self.used_slot_files(FILE_ATLAS) if atlas else self.used_slot_files(FILE_LOBE, level=0)


def read(lib, handle):
    """A BakeOutput from an ndfb_bake_result handle (not destroyed here)."""
    width, height = ctypes.c_uint32(), ctypes.c_uint32()
    levels = []
    for level in range(lib.ndfb_bake_result_level_count(handle)):
        _checked(lib.ndfb_bake_result_level_size(handle, level, ctypes.byref(width), ctypes.byref(height)))
        levels.append((width.value, height.value))
    slots = lib.ndfb_bake_result_lobe_slots(handle)
    used = (ctypes.c_uint8 * slots)()
    _checked(lib.ndfb_bake_result_slots_used(handle, used, slots))
    _checked(lib.ndfb_bake_result_atlas_size(handle, ctypes.byref(width), ctypes.byref(height)))
    atlas_size = (width.value, height.value)
    frames = []
    if atlas_size != (0, 0):
        frame = AtlasFrame()
        for level in range(len(levels)):
            _checked(lib.ndfb_bake_result_atlas_frame(handle, level, ctypes.byref(frame)))
            frames.append({"x": frame.x, "y": frame.y, "width": frame.width, "height": frame.height})
    files = []
    entry = BakeFile()
    for index in range(lib.ndfb_bake_result_file_count(handle)):
        _checked(lib.ndfb_bake_result_file(handle, index, ctypes.byref(entry)))
        files.append(WrittenFile(kind=entry.kind, level=entry.level, slot=entry.slot, name=entry.name.decode()))
    return BakeOutput(levels=levels, slots=slots, slots_used=[bool(u) for u in used], atlas_size=atlas_size,
                      atlas_frames=frames, files=files)


def _checked(status):
    if status != 0:  # only a bad handle or index: a bug here, not the user's input
        raise RuntimeError("reading the bake's result failed (status %d)" % status)
