"""The host's numpy dtypes and the kernels' structs must agree byte for byte (one source of truth)."""
import numpy as np
import pyopencl as cl
import pytest

from clrender.device import layout
from clrender.device.program import build_program


def _probe_source():
    # OpenCL C has no offsetof: take the address of the field of a struct at address 0.
    lines = ["#define OFFSET(T, f) ((uint)(ulong)(&(((__global T*)0)->f)))",
             "__kernel void probe(__global uint* out) {", "    uint i = 0;"]
    for name, fields in layout.STRUCTS.items():
        lines.append(f"    out[i++] = (uint)sizeof({name});")
        for f in fields:
            lines.append(f"    out[i++] = OFFSET({name}, {f[0]});")
    lines.append("}")
    return "\n".join(lines)


def _expected():
    out = []
    for name, fields in layout.STRUCTS.items():
        dt = layout.dtype(name)
        out.append(dt.itemsize)
        out.extend(dt.fields[f[0]][1] for f in fields)
    return np.array(out, np.uint32)


def test_struct_layouts_match_device(ctx, queue):
    prg = build_program(ctx, _probe_source())
    exp = _expected()
    out = np.zeros(len(exp), np.uint32)
    buf = cl.Buffer(ctx, cl.mem_flags.WRITE_ONLY, out.nbytes)
    prg.probe(queue, (1,), None, buf)
    cl.enqueue_copy(queue, out, buf)
    queue.finish()
    labels = [f"{n}.size" if j == 0 else f"{n}.{fields[j - 1][0]}"
              for n, fields in layout.STRUCTS.items() for j in range(len(fields) + 1)]
    mismatches = [(lab, int(e), int(o)) for lab, e, o in zip(labels, exp, out) if e != o]
    assert not mismatches, f"host/device layout differs (name, host, device): {mismatches}"


def test_float3_is_refused():
    layout.STRUCTS["_Bad"] = [("v", "float3")]
    try:
        with pytest.raises(ValueError):
            layout._layout(layout.STRUCTS["_Bad"])
    finally:
        del layout.STRUCTS["_Bad"]


def test_vectors_are_16_byte_aligned():
    for name in layout.STRUCTS:
        dt = layout.dtype(name)
        for field, (sub, off, *_) in dt.fields.items():
            if {f[0]: f[1] for f in layout.STRUCTS[name]}[field] in ("float4", "uint4"):
                assert off % 16 == 0, (name, field, off)
