"""The benchmark's figure (`clrender bench --plot`)."""
from __future__ import annotations

from pathlib import Path

from ..errors import ClrenderError


def plot(result: dict, path) -> Path:
    """Bars of samples/s per scene and device (with the min-max spread); with convergence data, a second
    panel of relMSE against render time (log-log)."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise ClrenderError('--plot needs matplotlib: pip install "clrender[plot]"') from None
    ok = [r for r in result["results"] if r["status"] == "ok"]
    curves = [r for r in ok if r.get("convergence")]
    fig, axes = plt.subplots(1, 2 if curves else 1, figsize=(12 if curves else 7, 4.5), squeeze=False)
    ax = axes[0][0]
    scenes = list(dict.fromkeys(r["scene"] for r in ok))
    devices = list(dict.fromkeys(r["device"] for r in ok))
    width = 0.8 / max(len(devices), 1)
    for j, d in enumerate(devices):
        xs, ys, lo, hi = [], [], [], []
        for i, s in enumerate(scenes):
            r = next((r for r in ok if r["scene"] == s and r["device"] == d), None)
            if r is None:
                continue
            sp = r["samples_per_second"]
            xs.append(i + (j - (len(devices) - 1) / 2) * width)
            ys.append(sp["median"] / 1e6)
            lo.append((sp["median"] - sp["min"]) / 1e6)
            hi.append((sp["max"] - sp["median"]) / 1e6)
        ax.bar(xs, ys, width, yerr=[lo, hi], capsize=3, label=d)
        for x, y, h in zip(xs, ys, hi):
            ax.annotate(f"{y:.2f}", (x, y + h), ha="center", va="bottom", fontsize=8,
                        xytext=(0, 2), textcoords="offset points")
    ax.set_xticks(range(len(scenes)))
    ax.set_xticklabels(scenes, rotation=15)
    ax.set_ylabel("M samples / s (median, min-max)")
    ax.set_title(f"clrender {result['clrender_version']} {result['git_revision'][:10]}")
    if devices:
        ax.legend(fontsize=8)
    if curves:
        ax2 = axes[0][1]
        for r in curves:
            c = r["convergence"]
            ax2.loglog([p["seconds"] for p in c], [p["relmse"] for p in c], "o-", ms=3,
                       label=f"{r['scene']} / {r['device']}")
        ax2.set_xlabel("render time (s)")
        ax2.set_ylabel("relMSE")
        ax2.set_title("convergence")
        ax2.grid(True, which="both", alpha=0.3)
        ax2.legend(fontsize=8)
    fig.tight_layout()
    from ..film import _atomic_write

    path = _atomic_write(Path(path), lambda tmp: fig.savefig(tmp, dpi=110))  # a reader never sees half a plot
    plt.close(fig)
    return path
