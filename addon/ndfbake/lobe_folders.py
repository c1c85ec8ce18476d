"""Where a material's lobe textures live on disk, and when they may go.

Naming. A bake writes a new folder beside the .blend named after the material,
`//<material>.ndfbake/`. A name with characters outside [A-Za-z0-9_.-] has them replaced by '_'
and gets '~' and a hash of the exact name appended (`//Metal_01~1a2b3c4d.ndfbake/` for
"Metal 01"), so no two names share a folder. A bake's folder is never written again: a re-bake
goes to `~2`, `~3`… while earlier ones exist, so Ctrl-Z after a re-bake or a Revert finds the
previous bake's files where its nodes expect them. A folder is new when nothing on disk has its
name (compared without case: the .blend may move to a case-insensitive disk), no material's bake
names it and no bake in progress has reserved it; this also keeps apart two .blend files side by
side with a material of the same name.

Deleting. A lobe folder may be needed by any .blend that was ever saved while naming it: this one
before a Save As, a Save Copy, a library another file appends the material from. So nothing is
deleted when a bake is replaced or reverted, nor when the file is saved (Ctrl-Z after a save must
still find the files). Each lobe folder keeps a list of the .blend files saved while using it
(USERS_FILE, written on every save; a Save Copy, whose path Blender does not pass on, pins the
folder for good). When this session's file is closed (another file opened, File › Revert, quit),
the folders this session wrote or let go are deleted if the file as last saved does not use them
and their list names no other .blend that exists. A folder from an older add-on without a list
is never deleted. Only the files a bake writes are deleted, then the folder if it is empty.
"""
import atexit
import hashlib
import os
import re

import bpy
from bpy.app.handlers import persistent

from . import material_scan

FOLDER_SUFFIX = ".ndfbake"
PENDING_SUFFIX = ".pending"
USERS_FILE = "blend_files.txt"
PINNED = "pinned: "  # a USERS_FILE line for a .blend whose path is unknown (a Save Copy)
# Bounds the search for a free folder: that many versions of one material on disk at once means
# something else is wrong (a folder that cannot be deleted), and the user should hear of it.
MAX_FOLDER_VERSIONS = 100


class FolderError(Exception):
    """No folder name is free (see new_folder)."""


def safe_name(name):
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", name).strip(".") or "material"


def folder_name(name, version=1):
    """'<name>.ndfbake', with '~<hash of the exact name>' where safe_name changed it ('~' never
    survives safe_name, so no other name's folder looks the same), and '~<version>' from 2 up."""
    safe = safe_name(name)
    if safe != name:
        safe += "~" + hashlib.sha1(name.encode("utf-8")).hexdigest()[:8]
    return safe + ("~%d" % version if version > 1 else "") + FOLDER_SUFFIX


def _key(path):
    return os.path.normcase(os.path.normpath(os.path.abspath(path))).casefold()


def is_bake_file(name):
    return name in ("report.json", USERS_FILE) or re.fullmatch(
        r"level\d+_(lobe|color)\d+\.exr|atlas_lobe\d+\.exr", name) is not None


def record_folder(rec):
    """The absolute folder of a bake: where its lobe images' files are (Blender remaps image paths
    when the .blend is saved elsewhere; the record's relative 'folder' it does not), else the
    record's folder."""
    for name in rec.get("images", []):
        image = bpy.data.images.get(name)
        if image is not None and image.filepath:
            return os.path.dirname(material_scan.image_file_path(image))
    return os.path.normpath(bpy.path.abspath(rec["folder"])) if rec.get("folder") else ""


def folder_users(folder, but=None):
    """The materials, other than `but`, whose bake is in `folder` (absolute)."""
    users = []
    for material in bpy.data.materials:
        rec = material_scan.record(material) if material is not but else None
        if rec and _key(record_folder(rec)) == _key(folder):
            users.append(material)
    return users


def _images_used_in(folder):
    """The images of files in `folder` that something still renders with: a user other than a node
    group, or a node group that is itself so used. (ID.users is not enough: after Material.copy()
    a removed group node can leave its group counted as used.)"""
    images = [image for image in bpy.data.images if image.source == "FILE" and image.filepath
              and _key(os.path.dirname(material_scan.image_file_path(image))) == _key(folder)]
    if not images:
        return []
    users = bpy.data.user_map(subset=images + list(bpy.data.node_groups))

    def used(datablock, seen):
        if datablock in seen:
            return False
        seen.add(datablock)
        return any(not isinstance(user, bpy.types.NodeTree) or used(user, seen) for user in users.get(datablock, ()))
    return [image for image in images if used(image, set())]


def folders_in_use():
    """{key: absolute path} of the folder of every bake in this .blend and of every lobe image
    something renders with."""
    folders = {}
    for rec in map(material_scan.record, bpy.data.materials):
        folder = record_folder(rec) if rec else ""
        if folder:
            folders[_key(folder)] = folder
    for image in bpy.data.images:
        if image.source == "FILE" and image.filepath and image.get("ndfbake") is not None:
            folder = os.path.dirname(material_scan.image_file_path(image))
            if _key(folder) not in folders and _images_used_in(folder):
                folders[_key(folder)] = folder
    return folders


# ---- new folders ---------------------------------------------------------------------------------

_reserved = set()  # keys of the folders of prepared bakes not yet finished or discarded


def _taken_on_disk(absolute):
    parent = os.path.dirname(absolute)
    try:
        names = {name.casefold() for name in os.listdir(parent)}
    except OSError:
        return False  # the bake will say why it cannot write there
    base = os.path.basename(absolute).casefold()
    return base in names or (base + PENDING_SUFFIX).casefold() in names


def new_folder(material):
    """('//…ndfbake', absolute path) for a new bake of `material`, reserved until release(); the
    absolute path is '' for an unsaved .blend. Raises FolderError when none is free."""
    if not bpy.data.filepath:
        return "//" + folder_name(material.name), ""
    for version in range(1, MAX_FOLDER_VERSIONS + 1):
        relative = "//" + folder_name(material.name, version)
        absolute = os.path.normpath(bpy.path.abspath(relative))
        if _key(absolute) not in _reserved and not _taken_on_disk(absolute) and not folder_users(absolute):
            _reserved.add(_key(absolute))
            return relative, absolute
    raise FolderError("%d lobe folders of '%s' are in the way beside the .blend (%s …): remove those no .blend "
                      "uses" % (MAX_FOLDER_VERSIONS, material.name, folder_name(material.name)))


def release(absolute):
    _reserved.discard(_key(absolute))


# ---- the session's folders, deleted when the file is closed -------------------------------------

_session = set()      # absolute folders this session's bakes wrote or let go
_saved_use = set()    # keys of the folders the file as last saved (or loaded) uses
_before_save = [None]  # the open file's (inode, mtime) before a save: unchanged after it, a Save Copy


def track(folder):
    """A folder this session let go (a re-bake, a Revert): a candidate for deletion when the file
    is closed."""
    if folder:
        _session.add(os.path.normpath(folder))


def _read_users(folder):
    try:
        with open(os.path.join(folder, USERS_FILE), encoding="utf-8") as f:
            return [line.rstrip("\n") for line in f if line.strip()]
    except OSError:
        return None


def _add_user(folder, line):
    users = _read_users(folder) or []
    if line in users:
        return
    path = os.path.join(folder, USERS_FILE)
    temporary = path + ".tmp"
    try:
        with open(temporary, "w", encoding="utf-8") as f:
            f.write("".join(u + "\n" for u in users + [line]))
        os.replace(temporary, path)
    except OSError as e:
        print("ndfbake: could not note %s in %s: %s" % (line, path, e.strerror))


def note_save():
    """After a save: every folder in use now lists this .blend (a Save Copy, which leaves the open
    file as it was on disk, pins them instead), and becomes what the saved file uses."""
    blend = bpy.data.filepath
    copy = _file_identity(blend) in (None, _before_save[0])
    in_use = folders_in_use()
    for folder in in_use.values():
        if os.path.isdir(folder):
            _add_user(folder, PINNED + "a copy of " + blend if copy else os.path.normpath(blend))
    if not copy:
        _saved_use.clear()
        _saved_use.update(in_use)


def delete_unused_folders(closing=True):
    """Deletes this session's folders that the file as last saved does not use and no other .blend
    lists (see above); with closing=False (a script that goes on), also those the file in memory
    uses are kept. Returns (files removed, [files not removed])."""
    current = _key(bpy.data.filepath) if bpy.data.filepath else ""
    keep = set(_saved_use) | (set() if closing else set(folders_in_use()))
    removed, left = 0, []
    for folder in sorted(_session):
        if _key(folder) in keep or not os.path.isdir(folder):
            if not os.path.isdir(folder):
                _session.discard(folder)
            continue
        users = _read_users(folder)
        if users is None and not _created_this_session(folder):
            continue  # an older bake's folder: who uses it is unknown
        if any(u.startswith(PINNED) or (_key(u) != current and os.path.exists(u)) for u in users or []):
            continue
        try:
            names = os.listdir(folder)
        except OSError as e:
            left.append("%s (%s)" % (folder, e.strerror))
            continue
        count, failed = delete_bake_files(folder, names)
        removed += count
        left += failed
        if not failed:
            _session.discard(folder)
    return removed, left


_created = set()


def created(folder):
    """A folder this session's bake wrote: a candidate for deletion when the file is closed, also
    before any save has listed who uses it."""
    _created.add(_key(folder))
    track(folder)


def _created_this_session(folder):
    return _key(folder) in _created


def delete_bake_files(folder, names):
    """Deletes the bake's own files (never anything else) and then the folder if it is empty."""
    removed, left = 0, []
    if folder and os.path.isdir(folder):
        for name in names:
            if not is_bake_file(name):
                continue
            path = os.path.join(folder, name)
            try:
                os.remove(path)
                removed += 1
            except FileNotFoundError:
                pass
            except OSError as e:
                left.append("%s (%s)" % (path, e.strerror))
        try:
            os.rmdir(folder)
        except OSError:
            pass
    return removed, left


def _file_identity(path):
    """(inode, mtime in ns) of a file, None if it is not there: Blender saves through a temporary
    file renamed into place, so a real save changes both."""
    try:
        st = os.stat(path)
    except OSError:
        return None
    return st.st_ino, st.st_mtime_ns


@persistent
def _on_save_pre(*_):
    _before_save[0] = _file_identity(bpy.data.filepath) if bpy.data.filepath else ("unsaved",)


@persistent
def _on_save_post(*_):
    note_save()


@persistent
def _on_load_pre(*_):
    _close_session()


@persistent
def _on_load_post(*_):
    _saved_use.clear()
    _saved_use.update(folders_in_use())


def _close_session():
    removed, left = delete_unused_folders(closing=True)
    if left:
        print("ndfbake: could not delete %s" % ", ".join(left))
    _session.clear()
    _created.clear()


_HANDLERS = (("save_pre", _on_save_pre), ("save_post", _on_save_post), ("load_pre", _on_load_pre),
             ("load_post", _on_load_post))
_installed = [False]


def install_handlers():
    """Called when the add-on is imported or registered: from then on every save, load and the
    exit keep the books. What the file uses now is what it uses as saved: nothing of ndfbake's
    can have changed it before this module was there."""
    for name, handler in _HANDLERS:
        handlers = getattr(bpy.app.handlers, name)
        if handler not in handlers:
            handlers.append(handler)
    if not _installed[0]:
        _installed[0] = True
        atexit.register(_close_session)
        try:
            _on_load_post()
        except AttributeError:
            pass  # bpy.data is not open yet while add-ons register at startup: load_post will do it


def remove_handlers():
    """For the add-on's unregister()."""
    for name, handler in _HANDLERS:
        handlers = getattr(bpy.app.handlers, name)
        if handler in handlers:
            handlers.remove(handler)


install_handlers()
