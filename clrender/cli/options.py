"""Options and argument types that several `clrender` commands share (each command's module adds its own)."""
from __future__ import annotations

import argparse
import math

from ..errors import ClrenderError


def defines(items) -> dict:
    """The -D name=value options as a dict."""
    out = {}
    for item in items or []:
        if "=" not in item:
            raise ClrenderError(f"-D expects name=value, got '{item}'")
        k, v = item.split("=", 1)
        if not k.strip():
            raise ClrenderError(f"-D expects name=value, got '{item}' (no name)")
        out[k.strip()] = v
    return out


def seconds(text: str) -> float:
    """argparse type for --time-limit: a positive, finite number of seconds."""
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of seconds, got '{text}'") from None
    if not (math.isfinite(v) and v > 0):
        raise argparse.ArgumentTypeError(f"must be a positive, finite number of seconds, got '{text}'")
    return v


def add_dialect_option(p) -> None:
    from ..scene.dialect import DIALECTS, ENV_VAR

    p.add_argument("--nori-dialect", choices=DIALECTS, default=None,
                   help=f"how to read Nori XML: upstream (wjakob/nori, EPFL; camera +x on the image's left, "
                        f"rotate axes normalised) or eth (ETH Zürich, Dartmouth; +x on the right, axes as "
                        f"written) or eth2023 (eth with the analytic sphere's u turned half a revolution, as ETH's "
                        f"course files up to 2023). Default: ${ENV_VAR}, else upstream")
