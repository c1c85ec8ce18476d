"""libndfbake's C declarations (native/include/ndfbake.h) as ctypes: the ABI version, status codes,
enums and option structures, for native.py's calls. No bpy; nothing is loaded here."""
import ctypes

# The ABI this module's structures and signatures are written against: the library's major
# (ndfb_abi_version()) must be ABI_MAJOR, its minor (ndfb_abi_minor()) at least ABI_MINOR. Limits
# and defaults are the library's (native.Library.max_lobes, ndfb_fit_options_init).
ABI_MAJOR = 2
ABI_MINOR = 0

# ndfb_status
OK = 0
ERROR_INVALID_ARGUMENT = 1
ERROR_FILE_NOT_FOUND = 2
ERROR_UNSUPPORTED_FORMAT = 3
ERROR_CORRUPT_FILE = 4
ERROR_IO = 5
ERROR_OUT_OF_MEMORY = 6
ERROR_CANCELLED = 7
ERROR_INTERNAL = 8

# enums
CONVENTION_OPENGL, CONVENTION_DIRECTX = 0, 1
WRAP_REPEAT, WRAP_CLAMP = 0, 1
BRDF_GGX, BRDF_BLINN_PHONG, BRDF_LAMBERT, BRDF_BECKMANN = 0, 1, 2, 3
PRECISION_HALF, PRECISION_FLOAT = 0, 1
FIT_PER_LEVEL, FIT_HIERARCHICAL = 0, 1
# ndfb_file_kind: what each file of a bake holds
FILE_LOBE, FILE_COLOR, FILE_ATLAS, FILE_MIP, FILE_SHADER, FILE_REPORT = 0, 1, 2, 3, 4, 5

PROGRESS_FN = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.c_char_p, ctypes.c_float)


class DecodeOptions(ctypes.Structure):
    _fields_ = [
        ("struct_size", ctypes.c_uint32),
        ("convention", ctypes.c_int),
        ("srgb", ctypes.c_int),
        ("max_pixels", ctypes.c_uint64),
    ]


class FitOptions(ctypes.Structure):
    _fields_ = [
        ("struct_size", ctypes.c_uint32),
        ("max_lobes", ctypes.c_uint32),
        ("tolerance", ctypes.c_float),
        ("brdf", ctypes.c_int),
        ("brdf_parameter", ctypes.c_float),
        ("wrap", ctypes.c_int),
        ("align", ctypes.c_int32),
        ("alignment_strength", ctypes.c_float),
        ("max_iterations", ctypes.c_uint32),
        ("method", ctypes.c_int),
        ("threads", ctypes.c_uint32),
        ("max_memory_bytes", ctypes.c_uint64),
        ("max_levels", ctypes.c_uint32),
        ("starts", ctypes.c_uint32),
        ("refine", ctypes.c_int32),
    ]


class WriteOptions(ctypes.Structure):
    _fields_ = [
        ("struct_size", ctypes.c_uint32),
        ("precision", ctypes.c_int),
        ("color_path", ctypes.c_char_p),
        ("source_name", ctypes.c_char_p),
        ("atlas", ctypes.c_int32),
        ("mipmap", ctypes.c_int32),
    ]


class BakeFile(ctypes.Structure):
    _fields_ = [
        ("kind", ctypes.c_int),
        ("level", ctypes.c_int32),
        ("slot", ctypes.c_int32),
        ("name", ctypes.c_char_p),
    ]


class AtlasFrame(ctypes.Structure):
    _fields_ = [
        ("x", ctypes.c_uint32),
        ("y", ctypes.c_uint32),
        ("width", ctypes.c_uint32),
        ("height", ctypes.c_uint32),
    ]


class Mesh(ctypes.Structure):
    _fields_ = [
        ("struct_size", ctypes.c_uint32),
        ("positions", ctypes.POINTER(ctypes.c_float)),
        ("vertex_count", ctypes.c_size_t),
        ("face_sizes", ctypes.POINTER(ctypes.c_uint32)),
        ("face_count", ctypes.c_size_t),
        ("corner_vertices", ctypes.POINTER(ctypes.c_uint32)),
        ("corner_count", ctypes.c_size_t),
        ("normals", ctypes.POINTER(ctypes.c_float)),
        ("normal_domain", ctypes.c_int),
        ("uvs", ctypes.POINTER(ctypes.c_float)),
        ("uv_domain", ctypes.c_int),
    ]


PER_CORNER, PER_VERTEX = 0, 1
