"""The command line's output layers: `--aov NAME,...` (Film.aov: albedo, normal, depth, position, variance, count)."""
from __future__ import annotations

from .errors import ClrenderError
from .film import AOVS, FEATURE_AOVS


def add_render_arguments(r) -> None:
    r.add_argument("--aov", metavar="NAME,...",
                   help=f"extra layers in the EXR, comma-separated: {', '.join(AOVS)} (albedo and normal of the first "
                        f"non-specular surface, as denoisers take them; depth and position of the first hit)")


def layers_from_args(args) -> tuple[str, ...]:
    """The layers --aov asks for, checked (ClrenderError naming the unknown one); () without --aov."""
    if not getattr(args, "aov", None):
        return ()
    names = tuple(dict.fromkeys(n.strip() for n in args.aov.split(",") if n.strip()))
    for n in names:
        if n not in AOVS:
            raise ClrenderError(f"--aov: unknown layer '{n}': expected some of {', '.join(AOVS)}")
    if getattr(args, "cluster", None) or getattr(args, "sample_range", None):
        raise ClrenderError("--aov is not supported with --cluster or --sample-range yet (their parts carry the "
                            "image's sums only)")
    return names


def needs_features(layers) -> bool:
    return any(n in FEATURE_AOVS for n in layers)
