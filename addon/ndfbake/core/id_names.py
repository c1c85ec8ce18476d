"""Names for the data-blocks a bake adds: Blender cuts an ID's name to 63 bytes of UTF-8 and, in
3.4, gives a name already taken to the ID renamed to it while renaming the ID that had it. So a
name is built as a body (the material's name, which may be long) cut to fit before a tail that
says what the ID is (" lobe 2", " atlas", a ".001" that keeps it from another's), and a free name
is looked for before any rename."""
import re

ID_NAME_BYTES = 63
_NUMBER = re.compile(r"^(.*?)(\.\d{3})?$", re.S)


def fit(body, tail=""):
    """body + tail within ID_NAME_BYTES: the body is cut (whole characters), the tail kept."""
    room = ID_NAME_BYTES - len(tail.encode("utf-8"))
    return body.encode("utf-8")[:room].decode("utf-8", errors="ignore") + tail


def numbered(name):
    """(body, number): an ID's name split before the ".NNN" that keeps it from another's ("" if none)."""
    body, number = _NUMBER.match(name).groups()
    return body, number or ""


def free(collection, body, tail="", own=None):
    """fit(body, tail), or with .001, .002… after the tail where another ID than `own` has it."""
    name, k = fit(body, tail), 0
    while name in collection and collection[name] != own:
        k += 1
        name = fit(body, "%s.%03d" % (tail, k))
    return name
