"""A bake's folder and files by name, with no Blender in it: the folder name a material gets
(blender/lobe_folders.py says which version is new and when a folder may go), which files are a
bake's own, and deleting exactly those. Used by the bake's native step (core/bake_job.py), which
runs off the main thread."""
import hashlib
import os
import re

from . import native

FOLDER_SUFFIX = ".ndfbake"
PENDING_SUFFIX = ".pending"


# The names Windows keeps for devices, whatever their case and extension ("CON", "nul.001",
# "Com1.x"): no folder can be named so there (a bake into "NUL.ndfbake" would even write nowhere),
# and a .blend may move to Windows with its folders.
_WINDOWS_DEVICE = re.compile(r"(CON|PRN|AUX|NUL|COM[0-9]|LPT[0-9])(?=\.|$)", re.IGNORECASE)


def safe_name(name):
    """`name` as a folder name on any system: characters outside [A-Za-z0-9_.-] become '_', no dot
    at either end (Windows drops trailing dots), '_' after a Windows device name ("CON_.001")."""
    safe = re.sub(r"[^A-Za-z0-9_.-]+", "_", name).strip(".") or "material"
    return _WINDOWS_DEVICE.sub(r"\1_", safe, count=1) if _WINDOWS_DEVICE.match(safe) else safe


def folder_name(name, version=1):
    """'<name>.ndfbake', with '~<hash of the exact name>' where safe_name changed it ('~' never
    survives safe_name, so no other name's folder looks the same), and '~<version>' from 2 up."""
    safe = safe_name(name)
    if safe != name:
        safe += "~" + hashlib.sha1(name.encode("utf-8")).hexdigest()[:8]
    return safe + ("~%d" % version if version > 1 else "") + FOLDER_SUFFIX


def path_key(path):
    return os.path.normcase(os.path.normpath(os.path.abspath(path))).casefold()


def is_bake_file(name):
    """Whether the library writes files so named (ndfb_is_bake_file). Without a usable library: no
    file is, so nothing is deleted."""
    lib, _ = native.status()
    return lib is not None and lib.is_bake_file(name)


def taken_on_disk(absolute):
    parent = os.path.dirname(absolute)
    try:
        names = {name.casefold() for name in os.listdir(parent)}
    except OSError:
        return False  # the bake will say why it cannot write there
    base = os.path.basename(absolute).casefold()
    return base in names or (base + PENDING_SUFFIX).casefold() in names


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
