"""A tiny XML writer for scene files: fixed number formatting and attribute order (byte-for-byte
reproducible output), property and transform elements, and a scene file with its description comment."""
import numpy as np

from .files import write_text


def fnum(x):
    """Fixed, short float formatting for XML values (no '-0')."""
    s = "%.6g" % (float(x) + 0.0)
    if s == "-0":
        s = "0"
    return s


def fvec(v):
    return ", ".join(fnum(x) for x in v)


class Node:
    def __init__(self, tag, attrs=(), children=(), comment=None):
        self.tag = tag
        self.attrs = list(attrs)
        self.children = [c for c in children if c is not None]
        self.comment = comment

    def render(self, indent=0):
        pad = "    " * indent
        out = []
        if self.comment:
            out.append(pad + "<!-- " + self.comment + " -->")
        a = "".join(' %s="%s"' % (k, v) for k, v in self.attrs)
        if self.children:
            out.append("%s<%s%s>" % (pad, self.tag, a))
            for c in self.children:
                out.extend(c.render(indent + 1))
            out.append("%s</%s>" % (pad, self.tag))
        else:
            out.append("%s<%s%s/>" % (pad, self.tag, a))
        return out


def obj_(tag, type_, *children, comment=None):
    return Node(tag, [("type", type_)], children, comment)


def p_float(name, v):
    return Node("float", [("name", name), ("value", fnum(v))])


def p_int(name, v):
    return Node("integer", [("name", name), ("value", "%d" % v)])


def p_str(name, v):
    return Node("string", [("name", name), ("value", v)])


def p_bool(name, v):
    return Node("boolean", [("name", name), ("value", "true" if v else "false")])


def p_point(name, v):
    return Node("point", [("name", name), ("value", fvec(v))])


def p_vector(name, v):
    return Node("vector", [("name", name), ("value", fvec(v))])


def p_color(name, v):
    if np.isscalar(v):
        v = (v, v, v)
    return Node("color", [("name", name), ("value", fvec(v))])


def t_translate(v):
    return Node("translate", [("value", fvec(v))])


def t_scale(v):
    if np.isscalar(v):
        v = (v, v, v)
    return Node("scale", [("value", fvec(v))])


def t_rotate(axis, angle):
    return Node("rotate", [("axis", fvec(axis)), ("angle", fnum(angle))])


def t_lookat(origin, target, up):
    return Node("lookat", [("origin", fvec(origin)), ("target", fvec(target)), ("up", fvec(up))])


def p_transform(name, *ops):
    return Node("transform", [("name", name)], ops)


def write_xml(path, description, root):
    """`description`: list of comment lines (what the scene shows, what a correct image looks like)."""
    for line in description:
        assert "--" not in line, line
    lines = ['<?xml version="1.0" encoding="utf-8"?>', "<!--"]
    lines += ["    " + l if l else "" for l in description]
    lines += ["-->"]
    lines += root.render(0)
    write_text(path, "\n".join(lines) + "\n")


def correct_image(expect):
    """Description lines 'Correct image: ...': its first 80 characters, then lines of at most 90, indented."""
    out = ["Correct image: " + expect[:80]]
    rest = expect[80:]
    while rest:
        k = rest.rfind(" ", 0, 90) if len(rest) > 90 else len(rest)
        out.append("    " + rest[:k].strip())
        rest = rest[k:].strip()
    return out
