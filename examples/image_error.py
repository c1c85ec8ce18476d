"""Image-level error of filtered renders against a reference, in linear light (numpy only).

Used by examples/demo_scene.py and tests/blender/test_addon_image_error.py; importable outside
Blender too. Images are float arrays (H, W, 3) of linear scene-referred RGB (EXR renders, no view
transform); masks are bool arrays (H, W). Row 0 is whichever row the caller's images start with:
nothing here depends on the orientation.

Two figures (../shared/DESIGN.md, "Ground truth and error"):
- block error: the root mean square, over every 4x4 window that lies wholly inside the region
  (stride 1), of the difference between the window's mean luminance (Rec. 709 weights) in the
  image and in the reference. It measures what filtering is for, the local brightness a pixel
  footprint averages to (over-shiny or too dark), and forgives sub-pixel differences in where
  detail lands (aliasing, pixel filters, noise): the EEVEE figure, and a second Cycles figure.
- pixel RMSE: the root mean square over the region's pixels and the three channels of the
  per-pixel difference: the Cycles figure (low-sample noise and sparkle count against it).
"""
import numpy as np

REC709 = np.array([0.2126, 0.7152, 0.0722], dtype=np.float64)
BLOCK = 4


def luminance(image):
    return np.asarray(image, dtype=np.float64)[..., :3] @ REC709


def box_downsample(image, factor):
    """Mean of each factor x factor block (the image's size must be a multiple of factor)."""
    image = np.asarray(image, dtype=np.float64)
    h, w = image.shape[0] // factor, image.shape[1] // factor
    image = image[:h * factor, :w * factor]
    return image.reshape(h, factor, w, factor, *image.shape[2:]).mean(axis=(1, 3))


def _window_sums(values, block):
    """Sum over every block x block window (valid positions only), via a summed-area table."""
    s = np.zeros((values.shape[0] + 1, values.shape[1] + 1), dtype=np.float64)
    s[1:, 1:] = np.cumsum(np.cumsum(values, axis=0), axis=1)
    return s[block:, block:] - s[:-block, block:] - s[block:, :-block] + s[:-block, :-block]


def block_means(image, block=BLOCK):
    """Mean luminance of every block x block window (stride 1): shape (H - block + 1, W - block + 1)."""
    return _window_sums(luminance(image), block) / float(block * block)


def block_mask(mask, block=BLOCK):
    """True for the windows whose every pixel is in `mask`."""
    return _window_sums(np.asarray(mask, dtype=np.float64), block) >= block * block - 0.5


def block_error(image, reference, mask, block=BLOCK):
    """RMS over the windows wholly inside `mask` of (mean luminance - reference's); NaN if none."""
    inside = block_mask(mask, block)
    if not inside.any():
        return float("nan")
    d = block_means(image, block)[inside] - block_means(reference, block)[inside]
    return float(np.sqrt(np.mean(d * d)))


def pixel_rmse(image, reference, mask):
    """RMS over the pixels in `mask` and the RGB channels of image - reference; NaN if none."""
    mask = np.asarray(mask, dtype=bool)
    if not mask.any():
        return float("nan")
    d = np.asarray(image, dtype=np.float64)[..., :3][mask] - np.asarray(reference, dtype=np.float64)[..., :3][mask]
    return float(np.sqrt(np.mean(d * d)))


def mean_luminance(image, mask):
    mask = np.asarray(mask, dtype=bool)
    return float(luminance(image)[mask].mean()) if mask.any() else float("nan")


def erode(mask, pixels=1):
    """Pixels whose 3x3 neighbourhood (repeated `pixels` times) lies in `mask`; the border is out."""
    mask = np.asarray(mask, dtype=bool)
    for _ in range(pixels):
        padded = np.pad(mask, 1, constant_values=False)
        out = np.ones_like(mask)
        for dy in (0, 1, 2):
            for dx in (0, 1, 2):
                out &= padded[dy:dy + mask.shape[0], dx:dx + mask.shape[1]]
        mask = out
    return mask


def ratio(a, b):
    return float(a / b) if b and np.isfinite(a) and np.isfinite(b) else float("nan")


def compare(images, reference, masks, block=BLOCK):
    """{region: {name: {block, rmse, mean}, 'reference': {mean}, 'windows', 'pixels'}} for every
    named image against `reference` over every named mask."""
    out = {}
    for region, mask in masks.items():
        entry = {"pixels": int(np.count_nonzero(mask)),
                 "windows": int(np.count_nonzero(block_mask(mask, block))),
                 "reference": {"mean": mean_luminance(reference, mask)}}
        for name, image in images.items():
            entry[name] = {"block": block_error(image, reference, mask, block),
                           "rmse": pixel_rmse(image, reference, mask),
                           "mean": mean_luminance(image, mask)}
        out[region] = entry
    return out
