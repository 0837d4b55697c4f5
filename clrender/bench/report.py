"""The benchmark's result: its JSON file, the human table, and the comparison of two results."""
from __future__ import annotations

import json
import os
from pathlib import Path

from ..errors import ClrenderError
from .measure import SCHEMA


# ------------------------------------------------------------------------------------------------------------
# Output
# ------------------------------------------------------------------------------------------------------------
def write_json(result: dict, path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(result, indent=1, sort_keys=False) + "\n")
    os.replace(tmp, path)
    return path


def load_json(path) -> dict:
    try:
        data = json.loads(Path(path).read_text())
    except OSError as exc:
        raise ClrenderError(f"cannot read {path}: {exc.strerror or exc}") from None
    except json.JSONDecodeError as exc:
        raise ClrenderError(f"{path}: not JSON ({exc})") from None
    if not isinstance(data, dict) or data.get("schema", "").split("/")[0] != SCHEMA.split("/")[0]:
        raise ClrenderError(f"{path}: not a clrender bench result (no '{SCHEMA}' schema field)")
    return data


def _fmt_rate(v):
    return "-" if v is None else f"{v / 1e6:.3g} M"


def _med(x):
    return None if not x else x.get("median")


def _fmt_s(v, ms=False):
    if v is None:
        return "-"
    return f"{v * 1e3:.3g} ms" if ms else f"{v:.3g} s"


def _fmt_bytes(v):
    if v is None:
        return "-"
    for unit, f in (("GiB", 2 ** 30), ("MiB", 2 ** 20), ("KiB", 2 ** 10)):
        if v >= f:
            return f"{v / f:.3g} {unit}"
    return f"{v} B"


def _table(headers, rows) -> str:
    widths = [max(len(str(h)), *(len(str(r[i])) for r in rows)) if rows else len(str(h))
              for i, h in enumerate(headers)]
    line = "  ".join(str(h).ljust(w) for h, w in zip(headers, widths))
    out = [line, "  ".join("-" * w for w in widths)]
    for r in rows:
        out.append("  ".join(str(c).ljust(w) for c, w in zip(r, widths)))
    return "\n".join(out)


def _spread(s):
    if not s or s.get("median") is None or len(s["values"]) < 2:
        return ""
    return f" ±{(s['max'] - s['min']) / 2 / s['median'] * 100:.0f}%"


def format_table(result: dict) -> str:
    """The human table: one line per scene x device (medians; ± = half the min-max spread)."""
    headers = ["scene", "device", "integrator", "res", "spp", "samples/s", "rays/s", "rays/spl", "pass",
               "build cold", "build warm", "load", "BVH", "pack", "dev mem", "peak RSS"]
    rows = []
    for r in result["results"]:
        if r["status"] != "ok":
            rows.append([r["scene"], r["device"], r.get("integrator") or "-", "", "", r["status"]]
                        + [""] * (len(headers) - 6))
            continue
        b = r.get("build", {})
        rays = r.get("rays")
        rows.append([
            r["scene"], r["device"], r["integrator"], f"{r['width']}x{r['height']}", r["spp"],
            _fmt_rate(_med(r["samples_per_second"])) + _spread(r["samples_per_second"]),
            _fmt_rate(_med(r.get("rays_per_second"))),
            "-" if not rays else f"{rays['per_sample']:.2f}",
            _fmt_s(_med(r["pass_seconds"]), ms=True),
            _fmt_s(b.get("cold_total")), _fmt_s(b.get("warm_total")),
            _fmt_s(r["load_seconds"]), _fmt_s(r["bvh_build_seconds"]), _fmt_s(r["pack_seconds"]),
            _fmt_bytes(r["device_memory_bytes"]), _fmt_bytes(r["host_peak_rss_bytes"]),
        ])
    text = _table(headers, rows)
    host = result.get("host", {})
    notes = [f"clrender {result['clrender_version']} ({result['git_revision'][:12]}), {result['timestamp']}, "
             f"load average {host.get('loadavg_start')} -> {host.get('loadavg_end')}; "
             f"medians of {result['settings']['repeat']} repeats, ± = half the min-max spread; "
             "build = program build + first launch (cold: fresh process, empty PoCL cache)"]
    seen = set()
    for r in result["results"]:
        if r["status"] != "ok" and (r["device"], r["reason"]) not in seen:
            seen.add((r["device"], r["reason"]))
            notes.append(f"{r['status']}: {r['device']}: {r['reason']}")
    for r in result["results"]:
        for c in (r.get("convergence") or [])[-1:]:
            notes.append(f"{r['scene']} on {r['device']}: relMSE {c['relmse']:.4g} after {c['spp']} spp, "
                         f"{c['seconds']:.3g} s")
    return text + "\n" + "\n".join(notes)


# ------------------------------------------------------------------------------------------------------------
# Compare
# ------------------------------------------------------------------------------------------------------------
_COMPARED = (("samples/s", lambda r: _med(r.get("samples_per_second"))),
             ("rays/s", lambda r: _med(r.get("rays_per_second"))),
             ("pass time", lambda r: _med(r.get("pass_seconds"))),
             ("build cold", lambda r: (r.get("build") or {}).get("cold_total")),
             ("build warm", lambda r: (r.get("build") or {}).get("warm_total")),
             ("BVH", lambda r: r.get("bvh_build_seconds")))


def compare(a: dict, b: dict) -> list[dict]:
    """Pair rows of two results by (scene hash, integrator), else (scene name, integrator); within a key, rows
    on the same device name pair first, the rest in order. Each pair gets ratios B/A."""
    oka = [r for r in a["results"] if r["status"] == "ok"]
    okb = [r for r in b["results"] if r["status"] == "ok"]
    pairs, used_b = [], set()
    for keyf in (lambda r: (r.get("scene_hash"), r["integrator"]), lambda r: (r["scene"], r["integrator"])):
        for ra in oka:
            if any(ra is p[0] for p in pairs):
                continue
            cands = [rb for rb in okb if id(rb) not in used_b and keyf(rb) == keyf(ra)]
            if not cands:
                continue
            same = [rb for rb in cands if rb["device"] == ra["device"]]
            rb = (same or cands)[0]
            used_b.add(id(rb))
            pairs.append((ra, rb))
    out = []
    for ra, rb in pairs:
        ratios = {}
        for name, f in _COMPARED:
            va, vb = f(ra), f(rb)
            ratios[name] = (vb / va) if va and vb is not None else None
        note = []
        ha, hb = ra.get("scene_hash") or "", rb.get("scene_hash") or ""
        if len(ha) != len(hb):
            # results before clrender-scene-hash-1 (64 digits, another hash) cannot say whether the files differ
            note.append("scene hashes of different clrender versions")
        elif ha != hb:
            note.append("scene files differ")
        if (ra["width"], ra["height"], ra["spp"]) != (rb["width"], rb["height"], rb["spp"]):
            note.append("resolution/spp differ")
        out.append({"scene": ra["scene"], "integrator": ra["integrator"], "device_a": ra["device"],
                    "device_b": rb["device"], "ratios": ratios, "note": "; ".join(note)})
    return out


def format_compare(a: dict, b: dict, name_a="A", name_b="B") -> str:
    pairs = compare(a, b)
    if not pairs:
        return f"no matching (scene, integrator) rows in {name_a} and {name_b}"
    headers = ["scene", "integrator", "device A -> B"] + [n for n, _ in _COMPARED] + ["note"]
    rows = []
    for p in pairs:
        dev = p["device_a"] if p["device_a"] == p["device_b"] else f"{p['device_a']} -> {p['device_b']}"
        rows.append([p["scene"], p["integrator"], dev]
                    + ["-" if p["ratios"][n] is None else f"{p['ratios'][n]:.3f}x" for n, _ in _COMPARED]
                    + [p["note"]])
    head = (f"ratios B/A (A = {name_a}: {a.get('git_revision', '?')[:12]} {a.get('timestamp', '')}; "
            f"B = {name_b}: {b.get('git_revision', '?')[:12]} {b.get('timestamp', '')}). "
            "samples/s and rays/s: > 1 = B faster; times: < 1 = B faster")
    return head + "\n" + _table(headers, rows)
