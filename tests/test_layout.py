"""The host's numpy dtypes and the kernels' structs must agree byte for byte (one source of truth)."""
import numpy as np
import pyopencl as cl
import pytest

from clrender.device import layout
from clrender.device.program import build_program


def _entries():
    """(label, C expression of the offset or size, expected value) for every struct, field and plugin member."""
    out = []
    for name, fields in layout.STRUCTS.items():
        dt = layout.dtype(name)
        out.append((f"sizeof {name}", f"sizeof({name})", dt.itemsize))
        out.extend((f"{name}.{f[0]}", f"OFFSET({name}, {f[0]})", dt.fields[f[0]][1]) for f in fields)
    for name, row in layout.ROWS.items():
        dt = layout.dtype(name)
        out.append((f"sizeof {name}", f"sizeof({name})", dt.itemsize))
        header = [f[0] for f in row.header]
        out.extend((f"{name}.{f}", f"OFFSET({name}, {f})", dt.fields[f][1]) for f in header)
        for member in dt.names:
            if member in header:
                continue
            sub, base = dt.fields[member][:2]
            for f in sub.names:
                out.append((f"{name}.p.{member}.{f}", f"OFFSET({name}, p.{member}.{f})", base + sub.fields[f][1]))
    return out


def _probe_source(entries):
    # OpenCL C has no offsetof: take the address of the field of a struct at address 0.
    lines = ["#define OFFSET(T, f) ((uint)(ulong)(&(((__global T*)0)->f)))",
             "__kernel void probe(__global uint* out) {"]
    lines += [f"    out[{i}] = (uint)({expr});" for i, (_, expr, _) in enumerate(entries)]
    lines.append("}")
    return "\n".join(lines)


def test_struct_layouts_match_device(ctx, queue):
    entries = _entries()
    assert any(".p.microfacet.alpha" in e[0] for e in entries) and any(".p.area.radiance" in e[0] for e in entries)
    prg = build_program(ctx, _probe_source(entries))
    exp = np.array([e[2] for e in entries], np.uint32)
    out = np.zeros(len(exp), np.uint32)
    buf = cl.Buffer(ctx, cl.mem_flags.WRITE_ONLY, out.nbytes)
    prg.probe(queue, (1,), None, buf)
    cl.enqueue_copy(queue, out, buf)
    queue.finish()
    mismatches = [(lab, int(e), int(o)) for (lab, _, e), o in zip(entries, out) if e != o]
    assert not mismatches, f"host/device layout differs (name, host, device): {mismatches}"


def test_float3_is_refused():
    layout.STRUCTS["_Bad"] = [("v", "float3")]
    try:
        with pytest.raises(ValueError):
            layout._layout(layout.STRUCTS["_Bad"])
    finally:
        del layout.STRUCTS["_Bad"]


def test_vectors_are_16_byte_aligned():
    for name in layout.STRUCTS:  # (plugin parameter structs: their float4 offsets are probed above)
        dt = layout.dtype(name)
        for field, (sub, off, *_) in dt.fields.items():
            if {f[0]: f[1] for f in layout.STRUCTS[name]}[field] in ("float4", "uint4"):
                assert off % 16 == 0, (name, field, off)


@pytest.mark.parametrize("macro", ["FILM_ARGS", "SPLAT_FILM_ARGS"])
def test_film_accumulators_match_device(ctx, queue, macro):
    # FILM_ARGS as the render kernels take them, SPLAT_FILM_ARGS as splat.cl's gather does: each accumulator's
    # element, sized by the device, against the dtype the host allocates, downloads and reads it with.
    names = [n for n, _t in getattr(layout, macro)]
    assert names[:3] == ["acc0", "acc1", "bad"]
    src = f"__kernel void probe({macro}, __global uint* out) {{\n"
    src += "".join(f"    out[{i}] = (uint)sizeof(*{n});\n" for i, n in enumerate(names)) + "}\n"
    prg = build_program(ctx, src)
    out = np.zeros(len(names), np.uint32)
    buf = cl.Buffer(ctx, cl.mem_flags.WRITE_ONLY, out.nbytes)
    dummy = cl.Buffer(ctx, cl.mem_flags.READ_WRITE, 16)
    prg.probe(queue, (1,), None, *([dummy] * len(names)), buf)
    cl.enqueue_copy(queue, out, buf)
    queue.finish()
    host = [np.dtype(dt).itemsize * int(np.prod(shape)) for dt, shape in map(layout.film_element, names)]
    assert out.tolist() == host


def test_film_buffers_by_render_kind():
    size = {n: np.dtype(dt).itemsize * int(np.prod(shape)) for n, *_ in layout.FILM_ACCUMULATORS
            for dt, shape in [layout.film_element(n)]}
    base = size["acc0"] + size["acc1"] + size["bad"]
    assert layout.film_buffers() == [("acc0", True), ("acc1", True), ("bad", True), ("rays", False)]
    assert dict(layout.film_buffers(count_rays=True))["rays"] is True
    assert dict(layout.film_buffers(splat=True))["acc2"] is True
    assert layout.film_bytes_per_pixel() == base
    assert layout.film_bytes_per_pixel(True) == base + size["rays"]
    assert layout.film_bytes_per_pixel(splat=True) == base + size["acc2"]


def test_textured_parameters_are_a_constant_and_a_texture_row():
    from clrender.textures.texture import TextureTable, param

    fields = [("c", "texture"), ("f", "float_texture"), ("n", "uint")]
    assert layout.expand(fields) == [("c", "float4"), ("c_tex", "uint"), ("f", "float"), ("f_tex", "uint"),
                                     ("n", "uint")]
    names, formats, offsets, size = layout._layout(fields)
    p = np.zeros(1, np.dtype({"names": names, "formats": formats, "offsets": offsets, "itemsize": size}))[0]
    table = TextureTable()
    assert not param(p, "c", [0.1, 0.2, 0.3], None, table) and not param(p, "f", 0.7, None, table)
    np.testing.assert_allclose(p["c"][:3], [0.1, 0.2, 0.3])
    np.testing.assert_allclose(p["f"], 0.7)
    assert p["c_tex"] == p["f_tex"] == layout.NONE
