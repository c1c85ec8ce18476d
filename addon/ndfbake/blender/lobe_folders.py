"""Where a material's lobe textures live on disk, and when they may go.

Naming. A bake writes a new folder beside the .blend named after the material,
`//<material>.ndfbake/`. A name with characters outside [A-Za-z0-9_.-] has them replaced by '_'
and gets '~' and a hash of the exact name appended (`//Metal_01~1a2b3c4d.ndfbake/` for
"Metal 01"), so no two names share a folder; so does a name Windows keeps for a device, with a
'_' after it (`//CON_~….ndfbake/` for "CON", `//nul_.001~….ndfbake/` for "nul.001"). A bake's
folder is never written again: a re-bake goes to `~2`, `~3`… while earlier ones exist, so Ctrl-Z
after a re-bake or a Revert finds the previous bake's files where its nodes expect them. A folder
is new when nothing on disk has its name (compared without case: the .blend may move to a
case-insensitive disk), no material's bake names it and no bake in progress has reserved it; this
also keeps apart two .blend files side by side with a material of the same name.

Deleting. A lobe folder may be needed by any .blend that was ever saved while using it: this one
(and its .blend1 backups) before a re-bake or a Revert, the file before a Save As, a Save Copy, a
library another file appends or links the material from, a copy made outside Blender. So a
folder is deleted automatically only if no .blend can know it: this session's bake wrote it, no
save of this session (any file, copies included) happened while a material or an image used it,
and Blender wrote no recovery file. Blender with a window writes recovery files that outlive the
session and may point at any folder the file used: autosaves every few minutes and quit.blend
(File > Recover > Last Session) as it quits, after freeing the file's data, with no handler for
either. So only a background Blender (scripts, render farms) deletes this session's unsaved
folders, when the file is closed (another file opened, quit) or through delete_unused_folders().
Otherwise a folder stays after a Revert or a re-bake; the Revert report names it, and the panel's
"Delete Unused Lobe Folders" (unused_folders) lists the folders beside the .blend that this file
does not use, neither as it is now nor as it was last opened or saved (a re-bake not saved yet
leaves the saved file using the old folder) nor through an undo step (a folder this session's
bake filled, until the file is closed), for the user to delete once no other .blend needs them.
Only the files a bake writes are deleted, then the folder if it is empty. A .blend written by a
script with bpy.data.libraries.write is no save to Blender's handlers: save the file (or keep its
folders) before the session closes, or a background session deletes folders it uses.
"""
import atexit
import os

import bpy
from bpy.app.handlers import persistent

from ..core.bake_job import BakeError
from ..core.folder_names import (FOLDER_SUFFIX, PENDING_SUFFIX, delete_bake_files, folder_name, path_key,
                                 taken_on_disk)
from ..shading import bake_record, material_scan
from . import app_handlers

# Bounds the search for a free folder: that many versions of one material on disk at once means
# something else is wrong (a folder that cannot be deleted), and the user should hear of it.
MAX_FOLDER_VERSIONS = 100


class FolderError(Exception):
    """No folder name is free (see new_folder)."""


def record_folder(rec):
    """The absolute folder of a bake: where its lobe images' files are (Blender remaps image paths
    when the .blend is saved elsewhere; the record's relative 'folder' it does not), else the
    record's folder."""
    images, folder = rec.get("images"), rec.get("folder")  # a damaged record may hold anything
    for name in images if isinstance(images, list) else []:
        image = bpy.data.images.get(name) if isinstance(name, str) else None
        if image is not None and image.filepath:
            return os.path.dirname(material_scan.image_file_path(image))
    return os.path.normpath(bpy.path.abspath(folder)) if isinstance(folder, str) and folder else ""


def folder_users(folder, but=None):
    """The materials, other than `but`, whose bake is in `folder` (absolute)."""
    users = []
    for material in bpy.data.materials:
        rec = bake_record.record(material) if material is not but else None
        if rec and path_key(record_folder(rec)) == path_key(folder):
            users.append(material)
    return users


# ---- new folders ---------------------------------------------------------------------------------

_reserved = set()  # keys of the folders of prepared bakes not yet finished or discarded
# Relative names ('//…ndfbake', case-folded) this session's bakes filled: never handed out again in
# the session, since an undo step may still hold image paths that name them relative to where the
# .blend was then (Ctrl-Z after a Save As elsewhere brings back the paths from before the remap).
_filled = set()


def new_folder(material):
    """('//…ndfbake', absolute path) for a new bake of `material`, reserved until release(); the
    absolute path is '' for an unsaved .blend. Raises FolderError when none is free."""
    if not bpy.data.filepath:
        return "//" + folder_name(material.name), ""
    for version in range(1, MAX_FOLDER_VERSIONS + 1):
        relative = "//" + folder_name(material.name, version)
        absolute = os.path.normpath(bpy.path.abspath(relative))
        if path_key(absolute) not in _reserved and relative.casefold() not in _filled and \
                not taken_on_disk(absolute) and not folder_users(absolute):
            _reserved.add(path_key(absolute))
            return relative, absolute
    raise FolderError("%d lobe folders of '%s' are in the way beside the .blend (%s …): remove those no .blend "
                      "uses" % (MAX_FOLDER_VERSIONS, material.name, folder_name(material.name)))


def release(absolute):
    _reserved.discard(path_key(absolute))


def filled(relative):
    """A bake's files went into `relative` (new_folder's name): not to be handed out again, nor
    offered for deletion while the file is open (an undo step may bring the bake back)."""
    _filled.add(relative.casefold())


def forget_undo_steps():
    """The file was closed, and with it the undo steps that could name this session's folders."""
    _filled.clear()


# ---- the session's folders: a background Blender deletes those no save used at close ------------

_created = {}      # key: absolute path of each folder this session's bakes wrote
_saved = set()     # keys of the folders something used while this session saved a .blend
# Keys of the folders the file used when it was last opened or saved: the .blend on disk may use
# them whatever the file holds now (a re-bake not saved yet). None: no load or save seen yet.
# A Save Copy counts as a save too (Blender 3.4's handlers cannot tell them apart).
_on_disk = None


def created(folder):
    """A folder this session's bake wrote: deleted when the file is closed unless a save used it.
    Only a background Blender keeps the books: with a window, recovery files may need any folder
    (module docstring), so none is ever deleted by itself. A script that bakes through bake.py
    without registering the add-on gets the handlers that keep them here, at its first bake."""
    if bpy.app.background:
        if not handlers_installed():
            install_handlers()
        _created[path_key(folder)] = os.path.normpath(folder)


def _referenced():
    """Keys of the folders this .blend refers to: every bake record's and every image's file's
    (whoever uses the image: a fake user or an asset keeps it in the saved file too)."""
    folders = set()
    for material in bpy.data.materials:
        rec = bake_record.record(material)
        if rec:
            try:
                folders.add(path_key(record_folder(rec)))
            except (AttributeError, TypeError, ValueError):
                pass  # a damaged record names no folder of ours
    for image in bpy.data.images:
        if image.source == "FILE" and image.filepath:
            folders.add(path_key(os.path.dirname(material_scan.image_file_path(image))))
    return folders


def note_save():
    """After any save (Save As and Save Copy too): the folders used now may be in a .blend on disk
    from now on, and are never deleted automatically."""
    try:
        referenced = _referenced()
    except Exception as e:  # never lose track: treat every folder of this session as saved
        print("ndfbake: keeping every lobe folder of this session (%s: %s)" % (type(e).__name__, e))
        referenced = set(_created)
    _saved.update(referenced & set(_created))
    global _on_disk
    _on_disk = referenced


def delete_unused_folders():
    """Deletes the folders this session's bakes wrote that no save used. Returns (files removed,
    [not removed])."""
    doomed = [folder for key, folder in sorted(_created.items()) if key not in _saved]
    removed, left = delete_folders(doomed)
    for folder in doomed:
        if not os.path.isdir(folder):
            del _created[path_key(folder)]
    return removed, left


def delete_folders(folders):
    """Deletes the bake files of each folder (then the folder, if empty). Returns (files removed,
    [what could not be removed])."""
    removed, left = 0, []
    for folder in folders:
        try:
            names = os.listdir(folder) if os.path.isdir(folder) else []
        except OSError as e:
            left.append("%s (%s)" % (folder, e.strerror))
            continue
        count, failed = delete_bake_files(folder, names)
        removed += count
        left += failed
    return removed, left


def unused_folders():
    """The lobe folders beside this .blend (by their suffix) that nothing in this file uses, for
    the user to delete (ndfbake.delete_unused_folders): other .blend files may still use them.
    A folder this session's bake filled is not offered until the file is closed: Ctrl-Z after a
    Revert or a re-bake brings back the nodes that read it.
    Also the pending folders of bakes that no longer run (left by a crash or a killed Blender)."""
    if not bpy.data.filepath:
        return []
    parent = os.path.dirname(os.path.abspath(bpy.data.filepath))
    undoable = {path_key(bpy.path.abspath(relative)) for relative in _filled}
    used = _referenced() | (_on_disk or set()) | undoable
    try:
        names = sorted(os.listdir(parent))
    except OSError:  # the .blend's folder went away: nothing beside it to list
        return []
    folders = []
    for name in names:
        path = os.path.join(parent, name)
        if not os.path.isdir(path):
            continue
        if name.endswith(FOLDER_SUFFIX) and path_key(path) not in used:
            folders.append(path)
        elif name.endswith(FOLDER_SUFFIX + PENDING_SUFFIX) and \
                path_key(path[:-len(PENDING_SUFFIX)]) not in _reserved:
            folders.append(path)
    return folders


def deleted_at_close(folder):
    """Whether closing the file will delete `folder` (this session wrote it, no save used it)."""
    return path_key(folder) in _created and path_key(folder) not in _saved


def forget_session():
    """Nothing of this session is deleted any more (the add-on is being turned off)."""
    _created.clear()
    _saved.clear()


# ---- a bake's pending folder (main thread) ---------------------------------------------------------

def commit_pending(job):
    """Renames a pending job's folder into its lobe folder (new: new_folder)."""
    if job.out_dir == job.final_dir:
        return
    try:
        os.rename(job.out_dir, job.final_dir)
    except OSError as e:
        raise BakeError("OUTPUT_NOT_WRITABLE", "cannot move the lobe textures of '%s' into %s: %s"
                        % (job.material_name, job.final_dir, e.strerror)) from None
    job.out_dir = job.final_dir
    created(job.final_dir)
    filled(job.folder)
    release(job.final_dir)


def discard_pending(job):
    """Deletes what a pending job wrote (nothing else: only its own files in its own folder) and
    gives its folder name back."""
    if job.out_dir != job.final_dir and os.path.isdir(job.out_dir):
        delete_bake_files(job.out_dir, os.listdir(job.out_dir))
    release(job.final_dir)


def _close_session():
    try:
        removed, left = delete_unused_folders()
        if left:
            print("ndfbake: could not delete %s" % ", ".join(left))
    except Exception as e:  # a handler must not raise into Blender's file loading or exit
        print("ndfbake: lobe folder cleanup failed (%s: %s)" % (type(e).__name__, e))
    forget_session()


@persistent
def _on_save_post(*_):
    note_save()


@persistent
def _on_load_pre(*_):
    _close_session()
    forget_undo_steps()


@persistent
def _on_load_post(*_):
    global _on_disk
    try:
        _on_disk = _referenced()
    except Exception as e:  # a handler must not raise into Blender's file loading
        print("ndfbake: could not list the lobe folders of %s (%s: %s)" % (bpy.data.filepath, type(e).__name__, e))
        _on_disk = None


def exit_session():
    """At exit: the session's unsaved folders go, as at any close of the file, and so do the
    handlers. A function in bpy.app.handlers keeps this module, and through it bpy, alive past
    Python's finalization, which the bpy module (PyPI's 4.2 and 4.5) cannot survive: 4.5 then
    hangs in its own exit (its sound thread's condition variable destroyed while waited on), 4.2
    crashes."""
    _close_session()
    app_handlers.remove(__name__, _HANDLERS)


_HANDLERS = (("save_post", _on_save_post), ("load_pre", _on_load_pre), ("load_post", _on_load_post))


def handlers_installed():
    return _on_save_post in bpy.app.handlers.save_post


def install_handlers():
    """Called when the add-on is registered, or at a background session's first bake (created):
    from then on every save and the closing of the file (load, exit) keep the books. Importing
    installs nothing. A reloaded module replaces its earlier handlers."""
    app_handlers.install(__name__, _HANDLERS)
    atexit.unregister(exit_session)
    atexit.register(exit_session)


def remove_handlers():
    """For the add-on's unregister(): the handlers go and this session's folders are kept."""
    app_handlers.remove(__name__, _HANDLERS)
    atexit.unregister(exit_session)
    forget_session()
