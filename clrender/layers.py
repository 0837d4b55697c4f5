"""The command line's output layers: `--aov NAME,...` (Film.aov: albedo, normal, depth, position, variance, count) and
`--denoise` (clrender/denoise.py: NAME.denoised.exr and .png beside the image)."""
from __future__ import annotations

from .errors import ClrenderError
from .film import AOVS, FEATURE_AOVS


def add_render_arguments(r) -> None:
    r.add_argument("--aov", metavar="NAME,...",
                   help=f"extra layers in the EXR, comma-separated: {', '.join(AOVS)} (albedo and normal of the first "
                        f"non-specular surface, as denoisers take them; depth and position of the first hit)")
    r.add_argument("--denoise", action="store_true",
                   help="also write the image denoised by Intel Open Image Denoise (guided by the albedo and normal "
                        "AOVs) as NAME.denoised.exr and .png beside it; needs the denoise extra")


def layers_from_args(args) -> tuple[str, ...]:
    """The layers --aov asks for, checked (ClrenderError naming the unknown one); () without --aov."""
    if getattr(args, "denoise", False):
        if getattr(args, "cluster", None) or getattr(args, "sample_range", None):
            raise ClrenderError("--denoise is not supported with --cluster or --sample-range yet: denoise the "
                                "merged image")
        from .denoise import available

        available()   # before rendering: a missing extra is said now, not after the render
    if not getattr(args, "aov", None):
        return ()
    names = tuple(dict.fromkeys(n.strip() for n in args.aov.split(",") if n.strip()))
    for n in names:
        if n not in AOVS:
            raise ClrenderError(f"--aov: unknown layer '{n}': expected some of {', '.join(AOVS)}")
    if getattr(args, "cluster", None):
        raise ClrenderError("--aov is not supported with --cluster yet (its tasks carry the image's sums only); "
                            "--sample-range parts carry them")
    return names


def needs_features(args, layers) -> bool:
    """Whether the render needs feature AOVs: for `layers`, or for --denoise in `args` (may be None)."""
    return bool(getattr(args, "denoise", False)) or any(n in FEATURE_AOVS for n in layers)


def write_denoised(film, out) -> tuple:
    """NAME.denoised.exr and NAME.denoised.png beside `out` (NAME.exr): the film denoised (metadata: the seconds the
    denoiser took)."""
    import time
    from pathlib import Path

    t0 = time.perf_counter()
    img = film.denoised()
    film.metadata["denoise_seconds"] = round(time.perf_counter() - t0, 4)
    base = Path(out).with_suffix("")
    exr, png = base.with_name(base.name + ".denoised.exr"), base.with_name(base.name + ".denoised.png")
    film.write_exr(exr, image=img)
    film.write_png(png, image=img)
    return exr, png
