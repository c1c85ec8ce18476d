"""Lighting of the grazing study: Blender's 8 studio worlds (converted once through the bpy module's
Python and cached), luminance, lookups, and Lighting.radiance (each world turned to a sun azimuth,
bright texels as point lights, plus the furnace / horizon / overhead probes). Calls numpy and the
bpy Python (subprocess) only; models are duck-typed (.l, .w, .eval), nothing here is imported."""
import os
import subprocess

import numpy as np

WORLD_DIR = "/usr/share/blender/datafiles/studiolights/world"
WORLDS = ("city", "courtyard", "forest", "interior", "night", "studio", "sunrise", "sunset")
WORLD_W, WORLD_H = 512, 256    # the worlds are box-downsampled 2x to this (0.7° texels)
BPY_PYTHON = os.path.expanduser("~/.cache/ndfbake/bpy-5.0/bin/python")
CACHE = os.path.expanduser("~/.cache/ndfbake/grazing_worlds_%dx%d.npz" % (WORLD_W, WORLD_H))


# ---------------------------------------------------------------------------------------------
# Lighting
_CONVERT = r"""
import bpy, numpy as np, sys
out = {}
for name in sys.argv[sys.argv.index('--') + 1:-1]:
    im = bpy.data.images.load('%s/%s.exr' % (WORLD_DIR, name))
    w, h = im.size
    px = np.empty(w * h * 4, np.float32)
    im.pixels.foreach_get(px)
    out[name] = px.reshape(h, w, 4)[::-1, :, :3]
np.savez_compressed(sys.argv[-1], **out)
"""


def load_worlds():
    """Blender's studio worlds as [H, W, 3] float arrays, row 0 = zenith side, box-downsampled to
    WORLD_W x WORLD_H; converted once (through the bpy module's Python) and cached."""
    if not os.path.exists(CACHE):
        raw = CACHE + ".raw.npz"
        script = _CONVERT.replace("WORLD_DIR", repr(WORLD_DIR))
        subprocess.run([BPY_PYTHON, "-c", script, "--"] + list(WORLDS) + [raw], check=True)
        data = np.load(raw)
        small = {}
        for name in WORLDS:
            img = data[name].astype(np.float64)
            h, w, _ = img.shape
            fy, fx = h // WORLD_H, w // WORLD_W
            small[name] = img.reshape(WORLD_H, fy, WORLD_W, fx, 3).mean((1, 3)).astype(np.float32)
        np.savez_compressed(CACHE, **small)
        os.remove(raw)
    data = np.load(CACHE)
    return {name: data[name] for name in WORLDS}


def luminance(img):
    return img[..., 0] * 0.2126 + img[..., 1] * 0.7152 + img[..., 2] * 0.0722


def brightest_azimuth(lum):
    """atan2(y, x) of a world's brightest texel, in Blender's lookup u = 0.5 - atan2(y, x)/2pi."""
    iy, ix = np.unravel_index(np.argmax(lum), lum.shape)
    u = (ix + 0.5) / lum.shape[1]
    return (0.5 - u) * 2 * np.pi, iy


def lookup(lum, l, rotation):
    """Bilinear lookup of a luminance map at directions l[N,3], the world turned by `rotation` about
    z (direction d is looked up at azimuth atan2(d) + rotation)."""
    h, w = lum.shape
    az = np.arctan2(l[:, 1], l[:, 0]) + rotation
    u = (0.5 - az / (2 * np.pi)) % 1.0
    el = np.arcsin(np.clip(l[:, 2], -1, 1))
    vv = 0.5 - el / np.pi                       # 0 at the zenith (row 0)
    x = u * w - 0.5
    y = np.clip(vv * h - 0.5, 0, h - 1.001)
    x0 = np.floor(x).astype(int)
    y0 = np.floor(y).astype(int)
    fx, fy = x - x0, y - y0
    x0 %= w
    x1 = (x0 + 1) % w
    return ((lum[y0, x0] * (1 - fx) + lum[y0, x1] * fx) * (1 - fy)
            + (lum[y0 + 1, x0] * (1 - fx) + lum[y0 + 1, x1] * fx) * fy)


SUN_THRESHOLD = 10.0   # texels brighter than this are drawn as point lights (exact BSDF), the
                       # rest by Monte Carlo: suns of 34000 in a 0.7° texel make sampled
                       # estimates noisy by 5-50% at 65k samples


class Lighting:
    """Luminance maps of the 8 worlds plus probes. `radiance(model, azimuth)` returns each one's
    radiance toward the view for a model (MapModel / ClosureModel), the world turned so that its
    brightest spot lies `azimuth` radians from the view's mirror direction (the mirror direction of
    v = +x is at azimuth pi). Texels above SUN_THRESHOLD are point lights evaluated exactly."""

    def __init__(self):
        self.names, self.maps, self.sun_az, self.suns = [], [], [], []
        for name, img in load_worlds().items():
            lum = luminance(img).astype(np.float64)
            h, w = lum.shape
            self.names.append(name)
            self.sun_az.append(brightest_azimuth(lum)[0])
            iy, ix = np.nonzero(lum > SUN_THRESHOLD)
            el = (0.5 - (iy + 0.5) / h) * np.pi
            az = (0.5 - (ix + 0.5) / w) * 2 * np.pi
            dw = np.cos(el) * (np.pi / h) * (2 * np.pi / w)
            self.suns.append((el, az, (lum[iy, ix] - SUN_THRESHOLD) * dw))
            self.maps.append(np.minimum(lum, SUN_THRESHOLD))

    def radiance(self, model, azimuth):
        l, w = model.l, model.w
        m = w > 0
        out = {}
        for name, lum, saz, (el, az, power) in zip(self.names, self.maps, self.sun_az, self.suns):
            rot = saz - (np.pi + azimuth)       # a direction at azimuth pi + azimuth sees the sun
            mc = float((w[m] * lookup(lum, l[m], rot)).sum() / len(w))
            a = az - rot
            ls = np.stack([np.cos(el) * np.cos(a), np.cos(el) * np.sin(a), np.sin(el)], -1)
            up = ls[:, 2] > 0
            out[name] = mc + float((model.eval(ls[up]) * power[up]).sum())
        z = np.clip(l[:, 2], 0, 1)
        out["furnace"] = float(w.mean())
        out["horizon"] = float((w * (z < np.sin(np.radians(10)))).mean())     # band 0-10°
        out["overhead"] = float((w * (z > np.cos(np.radians(30)))).mean())    # cap within 30° of zenith
        return out
