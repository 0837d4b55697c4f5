"""Command line of distributed rendering: `render --cluster` (Dask), `render --sample-range` (farm parts)
and `merge` (parts -> image). app.py calls in here."""
from __future__ import annotations

import sys
import time
from pathlib import Path

from ..errors import ClrenderError
from ..scenesource import SceneSource


def add_render_arguments(r) -> None:
    g = r.add_argument_group("distributed rendering")
    g.add_argument("--cluster", metavar="local[:N]|tcp://HOST:PORT|FILE",
                   help="render on Dask: a LocalCluster of N processes (default: one per usable device), "
                        "a running scheduler, or its scheduler file (needs clrender[cluster])")
    g.add_argument("--scene-files", choices=("ship", "shared"), default="ship",
                   help="with --cluster: ship the packed scene to the workers (default), or let each worker "
                        "load it from this path on a shared filesystem")
    g.add_argument("--tasks", type=int, metavar="N",
                   help="with --cluster: a fixed number of tasks (default: sized to about 2 s each)")
    g.add_argument("--sample-range", metavar="START:COUNT",
                   help="render samples START..START+COUNT-1 of every pixel and write an accumulator EXR "
                        "for `clrender merge` (farm mode)")


def parse_sample_range(text: str) -> tuple[int, int]:
    try:
        a, b = text.split(":")
        start, count = int(a), int(b)
    except ValueError:
        start = count = -1
    if start < 0 or count < 1:
        raise ClrenderError(f"--sample-range expects START:COUNT with START >= 0 and COUNT >= 1 "
                            f"(e.g. 0:64), got '{text}'")
    if start + count >= 2**32:  # samples are numbered with 32 bits (Renderer.render's bound)
        raise ClrenderError(f"--sample-range {text}: START + COUNT must stay below 2^32 = 4294967296, "
                            f"got {start + count}")
    return start, count


def cmd_render_distributed(args, defines: dict) -> int:
    """`render` with --cluster and/or --sample-range."""
    from ..parts import write_part

    from ..scene.dialect import resolve

    dialect = resolve(getattr(args, "nori_dialect", None))  # the option, else $CLRENDER_NORI_DIALECT, else upstream
    start, spp = 0, args.spp
    if args.sample_range:
        if args.spp is not None:
            raise ClrenderError("--sample-range START:COUNT sets the samples: leave out --spp")
        start, spp = parse_sample_range(args.sample_range)
    if args.tasks is not None and args.tasks < 1:
        raise ClrenderError("--tasks must be at least 1")
    if not args.cluster and (args.tasks is not None or args.scene_files != "ship"):
        raise ClrenderError("--tasks and --scene-files apply to --cluster renders only")
    from ..output import output_paths

    # the same -o rules as a plain render, checked before work; but a part, or what an interrupted cluster render
    # keeps, is an accumulator EXR
    out, _ = output_paths(args.output, args.scene,
                          exr_only="a --sample-range part is an accumulator EXR" if args.sample_range else
                          "--cluster writes an EXR (an accumulator EXR when interrupted)")
    say = lambda msg: print(f"clrender: {msg}", file=sys.stderr, flush=True)  # noqa: E731
    from ..layers import layers_from_args, needs_features

    layers = layers_from_args(args)   # a part carries the feature AOVs' sums and names its layers; merge adds them
    source = SceneSource(str(Path(args.scene).resolve()), defines, dialect)

    def write(film, scene_hash):
        """Write `film` where -o says; a sample range, or an image short of its samples, as a part."""
        incomplete = int(film.count.min()) < spp if film.count.size else False
        film.layers = layers
        if args.sample_range or incomplete:
            # A partial image keeps its true per-pixel counts (in a cluster render they differ by band): as a
            # part, it also merges with the rest of its samples later.
            write_part(film, out, scene_hash, args.seed, start, spp, dialect)
            what = f"accumulator EXR of samples {start}..{start + spp - 1}"
        else:
            film.write_exr(out)
            what = "EXR"
        png = film.write_png(out.with_suffix(".png")) if not args.sample_range else None
        return incomplete, what, png

    def partial(every, scene_hash=None):
        if every is None:
            return None
        return every, lambda film: write(film, scene_hash or film.metadata["scene_hash"])

    if args.cluster:
        from .. import cluster

        film = cluster.render(source.path, spp=spp, seed=args.seed, cluster=args.cluster, start_sample=start,
                              files=args.scene_files, defines=defines, dialect=dialect, device=args.device,
                              tasks=args.tasks, time_limit=args.time_limit, progress=not args.quiet, say=say,
                              partial=partial(args.partial_every), driver=args.driver,
                              reconstruction=args.reconstruction)
        scene_hash = film.metadata["scene_hash"]
    else:
        from ..renderer import Interrupted, Renderer

        t0 = time.perf_counter()
        scene_hash = source.content_hash()
        renderer = Renderer(source.load(), device=args.device, driver=args.driver,
                            reconstruction=args.reconstruction,
                            feature_aovs=needs_features(args, layers))
        say(f"{args.scene}: load {time.perf_counter() - t0:.2f} s; device {renderer.device_name}")
        try:
            film = renderer.render(spp=spp, seed=args.seed, time_limit=args.time_limit,
                                   progress=not args.quiet, start_sample=start,
                                   partial=partial(args.partial_every, scene_hash))
        except Interrupted:
            say("aborted (second Ctrl-C); nothing written")
            return 130
    s = film.stats
    rate = s.samples / s.seconds / 1e6 if s.seconds > 0 else 0.0
    incomplete, what, png = write(film, scene_hash)
    msg = (f"wrote {out} ({what})" + (f" and {png}" if png else "")
           + f": {int(film.count.min())}..{int(film.count.max())} spp per pixel in {s.seconds:.2f} s "
             f"({rate:.2f} M samples/s)")
    if incomplete:
        msg += f" [partial: {film.metadata.get('stopped_by', 'interrupted')}]"
    if s.dropped:
        msg += f"; {s.dropped} NaN/Inf samples dropped"
    say(msg)
    return 130 if s.interrupted else 0


def add_merge_parser(sub) -> None:
    m = sub.add_parser("merge", help="add accumulator EXRs of disjoint sample ranges into one image",
                       description="Check that the parts belong together (scene hash, seed, size, version, "
                                   "dialect; disjoint sample ranges, none missing) and write their image.")
    m.add_argument("parts", nargs="+", metavar="PART.exr", help="accumulator EXRs from --sample-range")
    m.add_argument("-o", "--output", required=True, metavar="OUT.exr", help="the merged image (EXR)")
    m.add_argument("--png", action="store_true", help="also write OUT.png")
    m.add_argument("--partial", action="store_true",
                   help="merge even if sample ranges are missing or a part was interrupted")
    m.add_argument("--denoise", action="store_true",
                   help="also write the merged image denoised (OUT.denoised.exr and .png; guided by the parts' "
                        "albedo and normal when they were rendered with --aov albedo,normal); needs the denoise extra")
    m.set_defaults(func=cmd_merge)


def cmd_merge(args) -> int:
    from ..output import check_writable
    from ..parts import merge_parts, read_part

    out = Path(args.output)
    if out.suffix.lower() != ".exr":
        raise ClrenderError(f"-o {out}: the merged image is an EXR; name it *.exr (add --png for a PNG)")
    for part in args.parts:  # the merged image is a plain EXR: writing it over a part would lose that part
        if out.resolve() == Path(part).resolve():
            raise ClrenderError(f"-o {out}: that is one of the parts being merged; name another file")
    for path in [out] + ([out.with_suffix(".png")] if args.png else []):
        check_writable(path, args.output)  # before the parts are read
    if args.denoise:
        from ..denoise import available

        available()   # a missing extra is said before any work
    film = merge_parts([read_part(p) for p in args.parts], allow_missing=args.partial)
    film.write_exr(out)
    written = [str(out)]
    if args.png:
        written.append(str(film.write_png(out.with_suffix(".png"))))
    if args.denoise:
        from ..layers import write_denoised

        written.append(str(write_denoised(film, out)[0]))
    m = film.metadata
    note = f"; missing samples {m['missing']}" if m["missing"] else ""
    print(f"clrender: merged {m['parts']} part(s), samples {m['sample_ranges']} ({m['spp']} spp){note}: "
          f"wrote {' and '.join(written)}", file=sys.stderr)
    return 0
