"""A corpus of malformed, hostile and odd-but-legal inputs to `clrender render`, one data-driven test.

Every case runs the command line in-process and checks: the exit status; that the message names the file
(with line, and column where the scene has one) or the option at fault; that no traceback escapes; and, for
failures, that nothing is left at the `-o` path (no image, no PNG, no temporary file).
"""
import os
import struct
import zlib
from dataclasses import dataclass, field

import pytest

from clrender.cli import main

QUAD = "v -2 -2 -1\nv 2 -2 -1\nv 2 2 -1\nv -2 2 -1\nf 1 2 3 4\n"
TRI = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
LIGHT = '<emitter type="area"><color name="radiance" value="1"/></emitter>'


def scene(body=None, integrator='<integrator type="normals"/>', camera=None, w=8, h=8, head=""):
    """A small valid scene; every part can be replaced. The camera is on lines 3-6, the body from line 7."""
    if camera is None:
        camera = (f'<camera type="perspective">\n'
                  f'    <integer name="width" value="{w}"/><integer name="height" value="{h}"/>\n'
                  f'    <transform name="toWorld"><lookat origin="0,0,3" target="0,0,0" up="0,1,0"/></transform>\n'
                  f'  </camera>')
    if body is None:
        body = ('<mesh type="sphere"><float name="radius" value="1"/></mesh>\n'
                '  <mesh type="obj"><string name="filename" value="quad.obj"/></mesh>')
    return f"{head}<scene>\n  {integrator}\n  {camera}\n  {body}\n</scene>\n"


def cam(op):
    """A scene whose camera transform is `op` (line 5)."""
    return scene(camera='<camera type="perspective">\n'
                        '    <integer name="width" value="8"/><integer name="height" value="8"/>\n'
                        f'    <transform name="toWorld">{op}</transform>\n'
                        '  </camera>')


def mesh(kind, name, extra=""):
    return scene(body=f'<mesh type="{kind}"><string name="filename" value="{name}"/>{extra}</mesh>')


def mitsuba(body):
    """A small Mitsuba 3 scene; `body` is on line 4."""
    return ('<scene version="3.0.0">\n'
            '  <sensor type="perspective"><transform name="to_world"><lookat origin="0,0,3" target="0,0,0" up="0,1,0"/>'
            '</transform>\n'
            '    <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>'
            '</sensor>\n'
            f'  {body}\n</scene>\n')


def bitmap(name):
    return mitsuba('<shape type="sphere"><bsdf type="diffuse"><texture type="bitmap" name="reflectance">'
                   f'<string name="filename" value="{name}"/></texture></bsdf></shape>')


def png_header_only(width, height):
    """A PNG that claims width x height 8-bit RGB pixels (and holds one byte of them)."""
    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(b"\0")) + chunk(b"IEND", b""))


def ply(fmt, nverts, nfaces, body, extra_header=""):
    head = (f"ply\nformat {fmt} 1.0\n{extra_header}element vertex {nverts}\nproperty float x\nproperty float y\n"
            f"property float z\nelement face {nfaces}\nproperty list uchar int vertex_indices\nend_header\n")
    return head.encode() + body


def binverts(*pts):
    return b"".join(struct.pack("<3f", *p) for p in pts)


def binface(*idx):
    return struct.pack("<B", len(idx)) + struct.pack(f"<{len(idx)}i", *idx)


GOOD_PLY_BODY = binverts((0, 0, 0), (1, 0, 0), (0, 1, 0)) + binface(0, 1, 2)
FIFO = object()   # marks a file to be created as a FIFO


@dataclass
class Case:
    id: str
    files: dict                       # name -> str | bytes | FIFO; "s.xml" is the scene
    argv: list = field(default_factory=list)
    code: int = 2
    names: tuple = ()                 # substrings stderr must contain (the file:line:col or the option)
    output: str | None = "o.exr"      # the -o argument (relative to the case folder); None: no -o


C = []


def case(id, files, names=(), code=2, argv=(), output="o.exr"):
    if isinstance(files, (str, bytes)):
        files = {"s.xml": files}
    files = {"quad.obj": QUAD, **files}
    C.append(Case(id, files, list(argv), code, tuple(names) if not isinstance(names, str) else (names,), output))


# ---- XML structure --------------------------------------------------------------------------------------------
case("xml-empty-file", "", "s.xml")
case("xml-only-declaration", '<?xml version="1.0"?>\n', "s.xml")
case("xml-unclosed", "<scene>\n  <integrator type='normals'>\n", "s.xml:3")
case("xml-mismatched", scene().replace("</camera>", "</camra>"), ("s.xml:6:", "mismatched"))
case("xml-two-roots", scene() + "<scene/>\n", ("s.xml:10:", "junk"))
case("xml-garbage-bytes", b"\x00\x01\x02\xff\xfe<scene>", "s.xml:1")
case("xml-invalid-utf8", scene().replace('value="1"', 'value="\udcff"').encode("utf-8", "surrogateescape"),
     "s.xml:7")
case("xml-text-content", scene().replace("<mesh type=\"sphere\">", "hello <mesh type=\"sphere\">"),
     ("s.xml:7:3", "unexpected text"))
case("xml-unknown-tag", scene().replace("<mesh type=\"sphere\">", "<blob/><mesh type=\"sphere\">"),
     ("s.xml:7:3", "unknown tag <blob>"))
# The two formats told apart by the root's version attribute: a file of one read as the other says why
case("xml-mitsuba-scene-without-version", mitsuba('<shape type="sphere"/>').replace(' version="3.0.0"', ""),
     ("s.xml:2:3", "unknown tag <sensor>", 'version="3.0.0"', "read as a Nori scene"))
case("xml-nori-tags-in-a-mitsuba-scene", mitsuba('<mesh type="sphere"/>'),
     ("s.xml:4:3", "unknown tag <mesh>", "Nori's", "version attribute"))
case("xml-unknown-attribute", scene().replace('<mesh type="sphere">', '<mesh type="sphere" size="2">'),
     ("s.xml:7:23", "size"))
case("xml-missing-type", scene().replace('<mesh type="sphere">', "<mesh>"), ("s.xml:7:3", "'type'"))
case("xml-duplicate-attribute", scene().replace('<mesh type="sphere">', '<mesh type="sphere" type="obj">'),
     ("s.xml:7:", "duplicate attribute"))
case("xml-wrong-root", "<bsdf type='diffuse'/>\n", ("s.xml:1:1", "root"))
case("xml-test-root", "<test type='ttest'/>\n", ("s.xml:1:1", "clrender test"))
case("xml-deep-nesting", "<scene>" + "<bsdf type='diffuse'>" * 100000 + "</bsdf>" * 100000 + "</scene>",
     ("s.xml:1:", "nested more than"))
case("xml-deep-nesting-lines", "<scene>\n" + "<mesh type='sphere'>\n" * 5000 + "</mesh>\n" * 5000 + "</scene>",
     ("s.xml:201:1", "nested more than"))
case("xml-unknown-encoding", '<?xml version="1.0" encoding="x-klingon"?>\n' + scene(),
     ("s.xml:1:1", "x-klingon"))
case("xml-unknown-encoding-utf99", '<?xml version="1.0" encoding="utf-99"?>\n' + scene(), ("s.xml:1:1", "utf-99"))
case("xml-billion-laughs",
     '<?xml version="1.0"?>\n<!DOCTYPE scene [<!ENTITY a "aaaaaaaaaa"><!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;">'
     '<!ENTITY c "&b;&b;&b;&b;&b;&b;&b;&b;">]>\n<scene><integrator type="&c;"/></scene>\n', "s.xml:")
case("xml-external-entity",
     '<?xml version="1.0"?>\n<!DOCTYPE scene [<!ENTITY x SYSTEM "file:///etc/passwd">]>\n'
     '<scene><integrator type="&x;"/></scene>\n', "s.xml:")
case("xml-comment-unclosed", scene().replace("<scene>", "<scene><!-- oops"), "s.xml:")
case("xml-cdata-text", scene().replace('<mesh type="sphere">', '<![CDATA[x]]><mesh type="sphere">'),
     ("s.xml:7:", "unexpected text"))
case("xml-nul-in-attribute", scene().replace('value="1"', 'value="1\x00"'), "s.xml:7")
case("xml-default-bad-name", scene().replace("<scene>", '<scene><default name="1x" value="2"/>'),
     ("s.xml:1:", "valid variable name"))
case("xml-undefined-variable", scene().replace('value="1"/></mesh>', 'value="$r"/></mesh>', 1),
     ("s.xml:7:", "$r"))

# ---- numbers: NaN / Inf / overflow wherever a number is read ------------------------------------------------
for what, op in [("translate-nan", '<translate value="nan, 0, 0"/><lookat origin="0,0,3" target="0,0,0" up="0,1,0"/>'),
                 ("translate-inf", '<translate value="0, inf, 0"/><lookat origin="0,0,3" target="0,0,0" up="0,1,0"/>'),
                 ("rotate-angle-nan", '<rotate axis="0,1,0" angle="nan"/><lookat origin="0,0,3" target="0,0,0" up="0,1,0"/>'),
                 ("rotate-axis-inf", '<rotate axis="0,-inf,0" angle="10"/><lookat origin="0,0,3" target="0,0,0" up="0,1,0"/>'),
                 ("lookat-origin-nan", '<lookat origin="NaN,0,3" target="0,0,0" up="0,1,0"/>'),
                 ("lookat-target-infinity", '<lookat origin="0,0,3" target="Infinity,0,0" up="0,1,0"/>'),
                 ("lookat-up-overflow", '<lookat origin="0,0,3" target="0,0,0" up="0,1e999,0"/>'),
                 ("scale-nan", '<scale value="nan"/><lookat origin="0,0,3" target="0,0,0" up="0,1,0"/>'),
                 ("matrix-nan", '<matrix value="1 0 0 0 0 1 0 0 0 0 1 nan 0 0 0 1"/>'),
                 ("matrix-neg-inf", '<matrix value="1 0 0 0 0 1 0 0 0 0 1 -inf 0 0 0 1"/>')]:
    case(f"number-camera-{what}", cam(op), ("s.xml:5:", "finite"))
case("number-sphere-center-nan", scene(body='<mesh type="sphere"><point name="center" value="0,nan,0"/></mesh>'),
     ("s.xml:7:", "center", "not a number"))
case("number-sphere-radius-inf", scene(body='<mesh type="sphere"><float name="radius" value="inf"/></mesh>'),
     ("s.xml:7:", "radius", "infinite"))
case("number-fov-nan", scene().replace('<integer name="height" value="8"/>',
                                       '<integer name="height" value="8"/><float name="fov" value="nan"/>'),
     ("s.xml:4:", "fov"))
case("number-albedo-nan", scene(body='<mesh type="sphere"><bsdf type="diffuse"><color name="albedo" '
                                     'value="0.5, nan, 0.5"/></bsdf></mesh>'), ("s.xml:7:", "albedo"))
case("number-radiance-inf", scene(body='<mesh type="sphere">' + LIGHT.replace('"1"', '"inf"') + '</mesh>'),
     ("s.xml:7:", "radiance"))
case("number-point-light-nan", scene(body='<emitter type="point"><point name="position" value="nan,0,0"/>'
                                          '<color name="power" value="1"/></emitter>'), ("s.xml:7:", "position"))
case("number-mesh-transform-nan", scene(body='<mesh type="obj"><string name="filename" value="quad.obj"/>'
                                             '<transform name="toWorld"><translate value="0,0,nan"/></transform>'
                                             '</mesh>'), ("s.xml:7:", "translate"))
case("number-width-overflow", scene().replace('name="width" value="8"', 'name="width" value="99999999999999999999"'),
     ("s.xml:4:", "width"))
case("number-width-float", scene().replace('name="width" value="8"', 'name="width" value="8.5"'),
     ("s.xml:4:", "integer"))
case("number-width-zero", scene(w=0), ("s.xml:4:", "width"))
case("number-height-negative", scene(h=-3), ("s.xml:4:", "height"))
case("number-sample-count-overflow", scene(integrator='<integrator type="normals"/><sampler type="independent">'
                                                      '<integer name="sampleCount" value="99999999999"/></sampler>'),
     ("s.xml:2:", "sampleCount"))
case("number-empty", scene().replace('name="radius" value="1"', 'name="radius" value=""'), ("s.xml:7:", "empty"))
case("number-garbage", scene().replace('name="radius" value="1"', 'name="radius" value="1,,x"'),
     ("s.xml:7:", "bad number 'x'"))
case("number-too-many", scene().replace('origin="0,0,3"', 'origin="0,0,3,4"'), ("s.xml:5:", "needs 3"))
# finite in double precision but not in the single precision the device computes in (used to pass the check:
# a sphere of radius 1e39 exhausted the memory in the BVH build, a camera translated by 1e39 rendered black)
case("number-radius-beyond-float", scene(body='<mesh type="sphere"><float name="radius" value="1e39"/></mesh>'),
     ("s.xml:7:", "radius", "too large", "single precision"))
case("number-translate-beyond-float", cam('<translate value="-4e38,0,0"/><lookat origin="0,0,3" target="0,0,0" '
                                          'up="0,1,0"/>'), ("s.xml:5:", "-4e38", "too large"))
case("number-albedo-beyond-float", scene(body='<mesh type="sphere"><bsdf type="diffuse"><color name="albedo" '
                                              'value="0.5, 1e39, 0.5"/></bsdf></mesh>'), ("s.xml:7:", "albedo"))
case("number-sphere-extent-beyond-float", scene(body='<mesh type="sphere"><point name="center" value="3e38,0,0"/>'
                                                     '<float name="radius" value="3e38"/></mesh>'),
     ("s.xml:7:", "sphere", "single-precision"))
# Finite but too large for the single-precision intersection tests: such a shape used to vanish from the image.
case("number-sphere-radius-1e20", scene(body='<mesh type="sphere"><point name="center" value="0,0,-1.1e20"/>'
                                             '<float name="radius" value="1e20"/></mesh>'),
     ("s.xml:7:", "sphere", "1e+18", "overflow"))
case("number-hex", scene().replace('name="radius" value="1"', 'name="radius" value="0x10"'), ("s.xml:7:", "0x10"))
case("number-max-depth-beyond-32-bits", scene(integrator='<integrator type="path_mis"><integer name="maxDepth" '
                                                    'value="99999999999"/></integrator>'),
     ("s.xml:2:", "maxDepth", "2147483647"))  # was an OverflowError traceback while packing
case("number-mitsuba-max-depth-beyond-32-bits",
     mitsuba('<integrator type="path"><integer name="max_depth" value="99999999999"/></integrator>'),
     ("s.xml:4:", "max_depth", "2147483647"))
# Filters so narrow that their single-precision weights vanish used to render a black image without a word.
for kind in ("tent", "mitchell", "box"):
    case(f"number-filter-{kind}-radius-1e-30",
         scene().replace('<integer name="height" value="8"/>', '<integer name="height" value="8"/><rfilter type="'
                         f'{kind}"><float name="radius" value="1e-30"/></rfilter>'), ("s.xml:4:", "radius", "1e-30"))
case("number-gaussian-too-narrow-for-stddev",
     scene().replace('<integer name="height" value="8"/>', '<integer name="height" value="8"/><rfilter '
                     'type="gaussian"><float name="radius" value="1e-4"/></rfilter>'), ("s.xml:4:", "too narrow"))
case("boolean-yes", scene(integrator='<integrator type="ao"><boolean name="x" value="yes"/></integrator>'),
     ("s.xml:2:", "boolean"))
case("number-max-depth", scene(integrator='<integrator type="path_mis"><integer name="maxDepth" value="-7"/>'
                                          '</integrator>'), ("s.xml:2:", "maxDepth"))

# ---- semantics -------------------------------------------------------------------------------------------------
case("plugin-unknown-integrator", scene(integrator='<integrator type="magic"/>'), ("s.xml:2:", "magic"))
case("plugin-unknown-bsdf", scene(body='<mesh type="sphere"><bsdf type="velvet"/></mesh>'), ("s.xml:7:", "velvet"))
case("plugin-unused-property", scene().replace('name="radius"', 'name="radiuss"'), ("s.xml:7:", "radiuss"))
case("plugin-property-twice", scene().replace('<float name="radius" value="1"/>',
                                               '<float name="radius" value="1"/><float name="radius" value="2"/>'),
     ("s.xml:7:", "twice"))
case("plugin-no-camera", "<scene>\n  <integrator type='normals'/>\n</scene>\n", ("s.xml:1:1", "camera"))
case("plugin-no-integrator", scene(integrator=""), ("s.xml:1:1", "integrator"))
case("plugin-two-cameras", scene(body=scene().split("\n  ", 2)[2].split("\n  <mesh")[0]), ("s.xml:7:", "camera"))
case("plugin-area-at-scene-level", scene(body=LIGHT), ("s.xml:7:", "area emitter"))
case("plugin-point-in-mesh", scene(body='<mesh type="sphere"><emitter type="point"><color name="power" '
                                        'value="1"/></emitter></mesh>'), ("s.xml:7:", "only area emitters"))
case("plugin-negative-radius", scene().replace('name="radius" value="1"', 'name="radius" value="-1"'),
     ("s.xml:7:", "radius"))
case("plugin-singular-scale", scene(body='<mesh type="obj"><string name="filename" value="quad.obj"/>'
                                         '<transform name="toWorld"><scale value="0"/></transform></mesh>'), "s.xml:7:")
case("plugin-camera-projective-matrix", cam('<matrix value="1 0 0 0 0 1 0 0 0 0 1 3 0 0 1 1"/>'),
     ("s.xml:5:", "affine"))  # its last row used to be dropped: a black image
case("plugin-fov-180", scene().replace('<integer name="height" value="8"/>',
                                       '<integer name="height" value="8"/><float name="fov" value="180"/>'),
     ("s.xml:4:", "fov"))
case("plugin-av-without-length", scene(integrator='<integrator type="av"/>'), ("s.xml:2:", "length"))
case("plugin-wrong-property-kind", scene().replace('<float name="radius" value="1"/>',
                                                   '<string name="radius" value="1"/>'), ("s.xml:7:", "radius"))
case("plugin-nested-wrongly", scene(body='<mesh type="sphere"><camera type="perspective"/></mesh>'),
     ("s.xml:7:", "cannot be nested"))

# ---- meshes: OBJ -----------------------------------------------------------------------------------------------
case("obj-missing", mesh("obj", "nowhere.obj"), ("s.xml:7:", "nowhere.obj"))
case("obj-empty-filename", mesh("obj", ""), ("s.xml:7:", "is empty"))  # was "it is a folder, not a file"
case("image-empty-filename", bitmap(""), ("s.xml:4:", "is empty"))
case("obj-is-a-folder", {"s.xml": mesh("obj", "sub"), "sub/x": ""}, ("s.xml:7:", "folder"))
case("obj-dev-zero", mesh("obj", "/dev/zero"), ("s.xml:7:", "/dev/zero", "device file"))
case("obj-dev-urandom", mesh("obj", "/dev/urandom"), ("s.xml:7:", "device file"))
case("obj-fifo", {"s.xml": mesh("obj", "pipe.obj"), "pipe.obj": FIFO}, ("s.xml:7:", "FIFO"))
case("obj-empty", {"s.xml": mesh("obj", "e.obj"), "e.obj": ""}, ("s.xml:7:", "e.obj", "no faces"))
case("obj-no-faces", {"s.xml": mesh("obj", "e.obj"), "e.obj": "v 0 0 0\nv 1 0 0\n"}, ("s.xml:7:", "no faces"))
case("obj-bad-number", {"s.xml": mesh("obj", "b.obj"), "b.obj": "v 0 0 0\nv 1 0 0\nv 1 x 0\nf 1 2 3\n"},
     ("s.xml:7:", "b.obj:3", "bad number"))
case("obj-nan-vertex", {"s.xml": mesh("obj", "b.obj"), "b.obj": "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n"},
     ("s.xml:7:", "b.obj:2", "not finite"))
case("obj-inf-normal", {"s.xml": mesh("obj", "b.obj"), "b.obj": TRI + "vn 0 0 inf\nf 1//1 2//1 3//1\n"},
     ("s.xml:7:", "b.obj:5", "not finite"))
case("obj-index-zero", {"s.xml": mesh("obj", "b.obj"), "b.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"},
     ("s.xml:7:", "b.obj:4", "index 0"))
case("obj-index-overflow", {"s.xml": mesh("obj", "b.obj"), "b.obj": TRI + "f 1 2 99999999999999999999\n"},
     ("s.xml:7:", "b.obj:5", "out of range"))
case("obj-negative-overflow", {"s.xml": mesh("obj", "b.obj"), "b.obj": TRI + "f -1 -2 -99999999999999999999\n"},
     ("s.xml:7:", "b.obj:5", "out of range"))
case("obj-index-out-of-range", {"s.xml": mesh("obj", "b.obj"), "b.obj": TRI + "f 1 2 9\n"},
     ("s.xml:7:", "b.obj:5", "out of range"))
case("obj-relative-out-of-range", {"s.xml": mesh("obj", "b.obj"), "b.obj": TRI + "f -1 -2 -4\n"},
     ("s.xml:7:", "b.obj:5", "relative"))
case("obj-bad-corner", {"s.xml": mesh("obj", "b.obj"), "b.obj": TRI + "f 1/2/3/4 2 3\n"},
     ("s.xml:7:", "b.obj:5", "corner"))
case("obj-two-corner-face", {"s.xml": mesh("obj", "b.obj"), "b.obj": TRI + "f 1 2\n"},
     ("s.xml:7:", "b.obj:5", "2 vertices"))
case("obj-binary-garbage", {"s.xml": mesh("obj", "b.obj"), "b.obj": bytes(range(256)) * 20}, ("s.xml:7:", "b.obj"))
case("obj-all-degenerate", {"s.xml": mesh("obj", "b.obj"), "b.obj": "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n"},
     ("s.xml:7:", "degenerate"))
case("obj-vertex-beyond-float", {"s.xml": mesh("obj", "b.obj"), "b.obj": "v 0 0 0\nv 1e39 0 0\nv 0 1 0\nf 1 2 3\n"},
     ("s.xml:7:", "b.obj", "beyond"))
case("obj-scaled-beyond-float", {"s.xml": mesh("obj", "b.obj", '<transform name="toWorld"><scale value="1e10"/>'
                                                               '</transform>'),
                                 "b.obj": "v 0 0 0\nv 1e30 0 0\nv 0 1e30 0\nf 1 2 3\n"},
     ("s.xml:7:", "b.obj", "world space"))
case("obj-quad-at-1e13", {"s.xml": mesh("obj", "b.obj", '<transform name="toWorld"><scale value="1e13"/></transform>'),
                          "b.obj": QUAD}, ("s.xml:7:", "b.obj", "1e+12", "overflow"))
# A byte order mark used to hide the first vertex: "index 3 is out of range (the file defines 2)", or, with more
# vertices, a silently different mesh.
case("legal-obj-utf8-bom", {"s.xml": mesh("obj", "n.obj"), "n.obj": "\ufeffv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"},
     (), code=0)
case("obj-utf16", {"s.xml": mesh("obj", "b.obj"), "b.obj": TRI.encode("utf-16")}, ("s.xml:7:", "b.obj:1", "UTF-16"))
case("obj-short-vertex", {"s.xml": mesh("obj", "b.obj"), "b.obj": "v 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"},
     ("s.xml:7:", "b.obj:1"))

# ---- meshes: PLY -----------------------------------------------------------------------------------------------
case("ply-truncated-binary", {"s.xml": mesh("ply", "m.ply"),
                              "m.ply": ply("binary_little_endian", 3, 1, GOOD_PLY_BODY[:20])},
     ("s.xml:7:", "m.ply", "truncated"))
case("ply-claims-2e9-vertices", {"s.xml": mesh("ply", "m.ply"),
                                 "m.ply": ply("binary_little_endian", 2000000000, 1, GOOD_PLY_BODY)},
     ("s.xml:7:", "m.ply:3", "2000000000"))
case("ply-claims-many-faces", {"s.xml": mesh("ply", "m.ply"),
                               "m.ply": ply("binary_little_endian", 3, 10**9, GOOD_PLY_BODY)},
     ("s.xml:7:", "m.ply:7", "face"))
case("ply-truncated-face-list", {"s.xml": mesh("ply", "m.ply"),
                                 "m.ply": ply("binary_little_endian", 3, 2, GOOD_PLY_BODY + binface(0, 1, 2)[:6])},
     ("s.xml:7:", "m.ply"))
case("ply-ascii-lying-header", {"s.xml": mesh("ply", "m.ply"),
                                "m.ply": ply("ascii", 3000, 1, b"0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")},
     ("s.xml:7:", "m.ply", "truncated"))
case("ply-no-end-header", {"s.xml": mesh("ply", "m.ply"), "m.ply": b"ply\nformat ascii 1.0\nelement vertex 3\n"},
     ("s.xml:7:", "m.ply", "end_header"))
case("ply-bad-format", {"s.xml": mesh("ply", "m.ply"), "m.ply": ply("binary_middle_endian", 3, 1, GOOD_PLY_BODY)},
     ("s.xml:7:", "m.ply:2", "format"))
case("ply-bad-type", {"s.xml": mesh("ply", "m.ply"),
                      "m.ply": ply("ascii", 3, 1, b"", ).replace(b"property float x", b"property quad x")},
     ("s.xml:7:", "m.ply:4", "quad"))
case("ply-negative-count", {"s.xml": mesh("ply", "m.ply"), "m.ply": ply("binary_little_endian", -3, 1, GOOD_PLY_BODY)},
     ("s.xml:7:", "m.ply:3", "element"))
case("ply-not-ply", {"s.xml": mesh("ply", "m.ply"), "m.ply": QUAD}, ("s.xml:7:", "m.ply", "not a PLY"))
case("ply-nan-vertex", {"s.xml": mesh("ply", "m.ply"),
                        "m.ply": ply("binary_little_endian", 3, 1, binverts((0, 0, 0), (float("nan"), 0, 0), (0, 1, 0))
                                     + binface(0, 1, 2))}, ("s.xml:7:", "m.ply", "non-finite"))
case("ply-index-out-of-range", {"s.xml": mesh("ply", "m.ply"),
                                "m.ply": ply("ascii", 3, 1, b"0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n")},
     ("s.xml:7:", "m.ply", "out of range"))
case("ply-no-faces", {"s.xml": mesh("ply", "m.ply"), "m.ply": ply("ascii", 3, 0, b"0 0 0\n1 0 0\n0 1 0\n")},
     ("s.xml:7:", "m.ply", "no faces"))
case("ply-property-before-element", {"s.xml": mesh("ply", "m.ply"),
                                     "m.ply": b"ply\nformat ascii 1.0\nproperty float x\nend_header\n"},
     ("s.xml:7:", "m.ply:3"))
case("ply-ascii-short-line", {"s.xml": mesh("ply", "m.ply"),
                              "m.ply": ply("ascii", 3, 1, b" 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")},  # found by fuzzing
     ("s.xml:7:", "m.ply:10", "record 0", "calls for 3"))
# A list whose length does not match its numbers, or a record with extra numbers, used to be read without a word
case("ply-ascii-list-length-lies", {"s.xml": mesh("ply", "m.ply"),
                                   "m.ply": ply("ascii", 4, 2, b"0 0 0\n1 0 0\n0 1 0\n1 1 0\n4 0 1 2\n3 0 2 3\n")},
     ("s.xml:7:", "m.ply:14", "record 0", "calls for 5"))
case("ply-ascii-extra-number", {"s.xml": mesh("ply", "m.ply"),
                                "m.ply": ply("ascii", 3, 1, b"0 0 0\n1 0 0 7\n0 1 0\n3 0 1 2\n")},
     ("s.xml:7:", "m.ply:11", "record 1", "calls for 3"))
case("ply-float-indices", {"s.xml": mesh("ply", "m.ply"),
                           "m.ply": ply("ascii", 3, 1, b"0 0 0\n1 0 0\n0 1 0\n3 0 1 2.5\n").replace(
                               b"list uchar int", b"list uchar float")},
     ("s.xml:7:", "m.ply:8", "must be integers"))  # 2.5 was read as vertex 2
case("ply-dev-zero", mesh("ply", "/dev/zero"), ("s.xml:7:", "device file"))

# ---- images (bitmap textures, environment maps; Mitsuba scenes) ---------------------------------------------------
# Each of the first three used to escape as a traceback or an unlocated "out of memory".
case("image-png-decompression-bomb", {"s.xml": bitmap("t.png"), "t.png": png_header_only(100000, 100000)},
     ("s.xml:4:", "t.png", "cannot read image"))
case("image-exr-corrupt", {"s.xml": bitmap("t.exr"), "t.exr": b"v/1\x01" + bytes(60)},
     ("s.xml:4:", "t.exr", "cannot read image"))
case("image-hdr-lying-resolution", {"s.xml": bitmap("t.hdr"), "t.hdr": b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n"
                                                                      b"-Y 1000000 +X 1000000\n" + bytes(8)},
     ("s.xml:4:", "t.hdr", "1000000 x 1000000"))
case("image-pfm-lying-resolution", {"s.xml": bitmap("t.pfm"), "t.pfm": b"PF\n1000000 1000000\n-1\n" + bytes(12)},
     ("s.xml:4:", "t.pfm", "ends before its 1000000 x 1000000 pixels"))
case("image-ppm16-truncated", {"s.xml": bitmap("t.ppm"), "t.ppm": b"P6\n300 200\n65535\n" + bytes(12)},
     ("s.xml:4:", "t.ppm", "ends before its 180000 samples"))
case("image-gif", {"s.xml": bitmap("t.gif"), "t.gif": b"GIF89a\x01\x00\x01\x00\x00\x00\x00;"},
     ("s.xml:4:", "t.gif", "unsupported image format", "PFM, PNG, JPEG, BMP, TGA"))
case("image-is-a-folder", {"s.xml": bitmap("sub"), "sub/x": ""}, ("s.xml:4:", "not a regular file"))
case("image-missing", bitmap("nowhere.png"), ("s.xml:4:", "nowhere.png", "not found"))

# ---- several broken meshes: one error names them all ------------------------------------------------------------
case("meshes-two-missing", scene(body='<mesh type="obj"><string name="filename" value="a.obj"/></mesh>\n'
                                      '  <mesh type="ply"><string name="filename" value="b.ply"/></mesh>'),
     ("s.xml:7:", "a.obj", "s.xml:8:", "b.ply", "2 mesh files"))
case("meshes-three-problems", {"s.xml": scene(body='<mesh type="obj"><string name="filename" value="a.obj"/></mesh>\n'
                                                   '  <mesh type="obj"><string name="filename" value="/dev/null"/></mesh>\n'
                                                   '  <mesh type="obj"><string name="filename" value="p.obj"/></mesh>'),
                               "p.obj": FIFO}, ("s.xml:7:", "s.xml:8:", "s.xml:9:", "3 mesh files"))

# ---- options -----------------------------------------------------------------------------------------------------
for value in ("nan", "inf", "-inf", "-1", "0", "abc", "1e999"):
    case(f"option-time-limit-{value}", scene(), "--time-limit", argv=["--time-limit", value])
for value in ("0", "-5", "4294967296", "x"):
    case(f"option-spp-{value}", scene(), "--spp", argv=["--spp", value])
case("option-define-without-name", scene(), "name=value", argv=["-D", "=1"])  # was silently ignored
case("option-seed-garbage", scene(), "--seed", argv=["--seed", "1.5"])
case("option-seed-negative", scene(), "--seed", argv=["--seed", "-1"])
case("option-seed-too-large", scene(), "--seed", argv=["--seed", "4294967296"])
case("option-device-index", scene(), "device index 99", argv=["--device", "99"])
case("option-device-name", scene(), "no-such-device", argv=["--device", "no-such-device"])
case("option-define-malformed", scene(), "name=value", argv=["-D", "oops"])
case("option-missing-scene", {}, "s.xml")
case("option-scene-is-folder", {"s.xml/x": ""}, "s.xml")
case("option-scene-is-fifo", {"s.xml": FIFO}, ("s.xml", "regular file"))

# ---- output --------------------------------------------------------------------------------------------------------
case("output-bmp", scene(), ("-o ", "img.bmp", ".exr, .png, .jpg, .jpeg, .hdr, .pfm"), output="img.bmp")
case("output-txt", scene(), ("-o ", "img.txt", "'.txt'"), output="img.txt")
case("output-proc", scene(), "/proc/clrender-x.exr", output="/proc/clrender-x.exr")
case("output-sys", scene(), "/sys/clrender-x.exr", output="/sys/clrender-x.exr")
case("output-under-a-file", {"s.xml": scene(), "f.txt": "x"}, ("f.txt", "not a folder"), output="f.txt/o.exr")
case("output-empty", scene(), "-o", output="")
case("output-png-sibling-is-folder", {"s.xml": scene(), "o.png/x": ""}, ("o.png", "folder"))
case("output-exr-is-fifo", {"s.xml": scene(), "o.exr": FIFO}, ("o.exr", "not a regular file"))

# ---- film size -----------------------------------------------------------------------------------------------------
case("film-65536-square", scene(w=65536, h=65536), ("s.xml:4:", "65536 x 65536", "width"))
case("film-60000-square", scene(w=60000, h=60000), ("s.xml:4:", "60000 x 60000", "width"))
case("film-tall", scene(w=4, h=65536 * 2), ("s.xml:4:", "height"))

# ---- odd but legal: these render (exit 0) ----------------------------------------------------------------------------
case("legal-plain", scene(), (), code=0)
case("legal-bom-and-blank-before-declaration", b"\xef\xbb\xbf  \n" + b'<?xml version="1.0"?>' + scene().encode(),
     (), code=0)
case("legal-crlf", scene().replace("\n", "\r\n"), (), code=0)
case("legal-latin1", ('<?xml version="1.0" encoding="iso-8859-1"?>\n<!-- \xe9t\xe9 -->\n' + scene()).encode("latin-1"),
     (), code=0)
case("legal-one-long-line", scene().replace("\n", " "), (), code=0)
case("legal-obj-negative-indices-tabs", {"s.xml": mesh("obj", "n.obj"),
                                         "n.obj": "v\t0 0 0\nv 1 0 0\nv 0 1 0\nf\t-3 -2 -1 # tri\n"}, (), code=0)
case("legal-ply-ascii", {"s.xml": mesh("ply", "m.ply"), "m.ply": ply("ascii", 3, 1, b"0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")},
     (), code=0)
case("legal-ply-binary", {"s.xml": mesh("ply", "m.ply"), "m.ply": ply("binary_little_endian", 3, 1, GOOD_PLY_BODY)},
     (), code=0)
case("legal-output-no-extension", scene(), (), code=0, output="img")
case("legal-output-upper-case", scene(), (), code=0, output="IMG.EXR")
case("legal-output-folder", {"s.xml": scene(), "outdir/.keep": ""}, (), code=0, output="outdir")
case("legal-output-new-folders", scene(), (), code=0, output="a/b/c.exr")
case("legal-no-emitter-warning", scene(integrator='<integrator type="path_mis"/>'),
     ("no emitter", "path_mis"), code=0)
case("legal-no-emitter-warning-direct", scene(integrator='<integrator type="direct_ems"/>'),
     ("no emitter",), code=0)
case("legal-no-emitter-warning-mitsuba", mitsuba('<shape type="sphere"/>'),
     ("no emitter", "'path' integrator", "<shape>"), code=0)  # it named the kernel 'path_mitsuba' and <mesh>
case("legal-time-limit", scene(), (), code=0, argv=["--time-limit", "0.5", "--spp", "1"])
case("legal-define", scene().replace('name="radius" value="1"', 'name="radius" value="$r"'), (), code=0,
     argv=["-D", "r=0.5"])


def _materialise(tmp_path, c: Case):
    for name, content in c.files.items():
        p = tmp_path / name
        p.parent.mkdir(parents=True, exist_ok=True)
        if content is FIFO:
            os.mkfifo(p)
        elif isinstance(content, bytes):
            p.write_bytes(content)
        else:
            p.write_text(content, encoding="utf-8", errors="surrogateescape")


def _argv(tmp_path, c: Case):
    argv = ["render", str(tmp_path / "s.xml"), "-q", "--spp", "1"]
    if c.output is not None:
        out = c.output if c.output == "" or c.output.startswith("/") else str(tmp_path / c.output)
        argv += ["-o", out]
    return argv + c.argv


def test_corpus_is_big_and_covers_every_category():
    assert len(C) >= 100
    assert len({c.id for c in C}) == len(C)
    prefixes = {c.id.split("-")[0] for c in C}
    for cat in ("xml", "number", "plugin", "obj", "ply", "meshes", "image", "option", "output", "film", "legal"):
        assert sum(c.id.split("-")[0] == cat for c in C) >= 2, cat
    assert prefixes <= {"xml", "number", "boolean", "plugin", "obj", "ply", "meshes", "image", "option", "output",
                        "film", "legal"}


@pytest.mark.parametrize("c", C, ids=[c.id for c in C])
def test_corpus(tmp_path, capsys, caplog, c):
    _materialise(tmp_path, c)
    before = {p for p in tmp_path.rglob("*")}
    try:
        code = main(_argv(tmp_path, c))
    except SystemExit as e:  # argparse's usage errors
        code = e.code
    err = capsys.readouterr().err + caplog.text  # warnings go through logging (pytest captures those)
    assert "Traceback" not in err, err
    assert code == c.code, err
    for name in c.names:
        assert name in err, f"{name!r} not in: {err}"
    if code != 0:
        assert err.strip(), "an error without a message"
        new = {p for p in tmp_path.rglob("*")} - before
        assert not new, f"left behind: {sorted(map(str, new))}"
    else:
        written = [p for p in tmp_path.rglob("*.exr")] + [p for p in tmp_path.rglob("*.EXR")]
        assert written, "nothing written"
