"""Mitsuba 0.6's low dynamic range film, which old scenes ask for (Mitsuba 3 has none): hdrfilm's size, crop
window and filter, and the tone map that makes its 8-bit image.

```xml
<film type="ldrfilm">
    <integer name="width" value="768"/>  ...     <!-- every size, crop and rfilter parameter of hdrfilm -->
    <string name="file_format" value="png"/>     <!-- png (default) or jpeg: clrender writes a PNG -->
    <string name="pixel_format" value="rgb"/>    <!-- rgb (default), rgba: colour; luminance, luminanceAlpha: grey -->
    <string name="tonemap_method" value="gamma"/>   <!-- gamma (default) or reinhard -->
    <float name="gamma" value="-1"/>             <!-- -1 (default): the sRGB curve; else x^(1/gamma) -->
    <float name="exposure" value="0"/>           <!-- gamma method: the image times 2^exposure first -->
    <float name="key" value="0.18"/>             <!-- reinhard: the log-average luminance becomes key -->
    <float name="burn" value="0"/>               <!-- reinhard: 0 to 1, how much the brightest part burns out -->
</film>
```
clrender renders as with any film and writes its linear EXR as always; the PNG beside it is this film's tone-mapped
8-bit image rather than the plain sRGB preview (:meth:`LdrFilm.tonemap`). The operators are Mitsuba 0.6's:
``gamma`` scales by 2^exposure, clamps to [0, 1] and applies the curve; ``reinhard`` (Reinhard et al. 2002, as
Mitsuba 0.6's Bitmap::tonemapReinhard) scales each pixel's luminance Y, keeping its chromaticity, by
key / (log-average luminance) and compresses it to Y (1 + Y / Lw²) / (1 + Y), Lw = the largest scaled luminance
times (1 - burn)², and then applies the gamma curve.
"""
from __future__ import annotations

import numpy as np

from ..errors import SceneError
from ..scene.registry import register
from .hdrfilm import HdrFilm

#: Rec. 709 / sRGB luminance weights, as Mitsuba's luminance of an RGB colour
LUMINANCE = np.array([0.212671, 0.715160, 0.072169])


@register("film", "ldrfilm", fmt="mitsuba")
class LdrFilm(HdrFilm):
    FORMATS = {"file_format": ("png", "jpeg"),
               "pixel_format": ("rgb", "rgba", "luminance", "luminancealpha", "luminance_alpha")}

    def __init__(self, props, children, spec):
        super().__init__(props, children, spec)
        self.grey = props.get_string("pixel_format", "rgb").lower().startswith("luminance")
        self.method = props.get_string("tonemap_method", "gamma").lower()
        if self.method not in ("gamma", "reinhard"):
            raise SceneError(f"tonemap_method '{self.method}' is not supported; clrender takes gamma, reinhard",
                             props.location("tonemap_method"))
        self.gamma = props.get_float("gamma", -1.0)
        if self.gamma == 0:
            raise SceneError("gamma must be -1 (sRGB) or a nonzero exponent", props.location("gamma"))
        self.exposure = props.get_float("exposure", 0.0)
        self.key = props.get_float("key", 0.18)
        self.burn = props.get_float("burn", 0.0)
        if not (self.key > 0 and 0 <= self.burn <= 1):
            bad = "key" if not self.key > 0 else "burn"
            raise SceneError("reinhard needs key > 0 and burn between 0 and 1", props.location(bad))
        props.get_bool("high_quality_edges", False)   # edge pixels filtered from beyond the film: no effect here

    def tonemap(self, image: np.ndarray) -> np.ndarray:
        """The (H, W, 3) uint8 image this film writes for the linear ``image``."""
        x = np.nan_to_num(np.asarray(image, np.float64), nan=0.0, posinf=0.0, neginf=0.0).clip(0.0, None)
        if self.method == "reinhard":
            y = x @ LUMINANCE
            if y.size and y.max() > 0:
                scale = self.key / np.exp(np.log(1e-3 + y).mean())
                lw = y.max() * scale * max(1e-8, 1.0 - self.burn) ** 2
                ys = y * scale
                lp = ys * (1 + ys / (lw * lw)) / (1 + ys)
                x = x * np.where(y > 0, lp / np.where(y > 0, y, 1.0), 0.0)[..., None]
        else:
            x = x * 2.0 ** self.exposure
        if self.grey:
            x = np.repeat((x @ LUMINANCE)[..., None], 3, axis=-1)
        x = x.clip(0.0, 1.0)
        if self.gamma < 0:
            x = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
        else:
            x = np.power(x, 1.0 / self.gamma)
        return np.clip(np.round(x * 255.0), 0, 255).astype(np.uint8)
