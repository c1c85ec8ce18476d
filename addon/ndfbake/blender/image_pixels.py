"""A normal map's pixels as Blender decodes them, in the layout the library takes.

Blender reads the image (every format and bit depth it supports, packed or on disk, with the
image's colour space and alpha settings), so the add-on's library needs no image decoder of its
own. material_scan.check_image has already refused what would make Blender's pixels differ from
the normals it renders (colour, not data, spaces; colours multiplied by alpha). Main thread only.
"""
from dataclasses import dataclass

# Float images whose components reach below this are stored as signed [-1, 1] normals, the others
# as [0, 1] colours: the library's rule for float files (io/normal_decode.cpp, has_signed_samples),
# so that a map baked from Blender's pixels and from its file decode alike.
SIGNED_FLOAT_THRESHOLD = -0.01
BYTE_MAX = 255.0  # the largest code of an 8-bit channel


@dataclass
class Pixels:
    """Rows top to bottom (as stored in image files), width * height * channels float32."""
    data: "numpy.ndarray"  # noqa: F821  (NumPy is imported where used: the add-on enables without it)
    width: int
    height: int
    channels: int
    signed: bool


class ImageReadError(Exception):
    """Blender could not decode the image; str() names it and its file."""


def read(image):
    """The pixels of `image` (bpy.types.Image) as Blender decodes them."""
    import numpy as np
    width, height = image.size  # reading the size loads the image if it is not loaded yet
    channels = image.channels
    if not image.has_data or width == 0 or height == 0 or channels == 0:
        raise ImageReadError("Blender could not read image '%s' (%s): the file is damaged or in a format it "
                             "does not read" % (image.name, image.filepath or "packed"))
    flat = np.empty(width * height * channels, dtype=np.float32)
    image.pixels.foreach_get(flat)
    # Blender's rows run bottom to top; the library's, as in files, top to bottom.
    rows = flat.reshape(height, width, channels)[::-1]
    if image.is_float:
        rgb = rows[..., :min(channels, 3)]
        finite = rgb[np.isfinite(rgb)]  # as the library: NaN and Inf say nothing of the encoding
        signed = finite.size > 0 and float(finite.min()) < SIGNED_FLOAT_THRESHOLD
        return Pixels(np.ascontiguousarray(rgb), width, height, rgb.shape[-1], signed)
    # An 8-bit image: Blender holds code k as the float k / 255. The library decodes a file's code
    # as (2k - 255) / 255 computed in double (io/normal_samples.h, code_to_component); handing it
    # that value, signed, gives the same normals to the last bit as `ndfbake bake FILE`, whose
    # EM would otherwise break a symmetric NDF's ties the other way (docs/fit.md, "Open problems").
    codes = np.rint(rows[..., :3].astype(np.float64) * BYTE_MAX)
    components = ((2.0 * codes - BYTE_MAX) / BYTE_MAX).astype(np.float32)
    return Pixels(np.ascontiguousarray(components), width, height, 3, True)
