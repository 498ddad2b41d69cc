#!/usr/bin/env python3
"""Writes the stitch-knot polylines of tests/data/knots (OBJ, one `l` element).

A thread through the tissue (the plane z = 0): from its first free end down into the tissue
at (-w/2, 0, 0), under it (a half ellipse), out at (+w/2, 0, 0) and up to its last free end;
above the surface the two strands twist about a common axis, one full turn per single throw
(two for a double throw), right-handed for a positive hand, or one strand runs straight and
the other winds around it (a half hitch). Pure Python, written apart from the C++ generator
(common/knot/stitch_knot_shapes.cc) from the same description: the hands of every knot are
checked here by a brute-force count of the crossing signs between the two strands of an
upright copy seen from the side, and the thread's clearance by node distances. Each thread
is then turned about z, moved in xy and given noise of 10 % of the diameter.

Usage: python3 generate_stitch_knots.py [OUTPUT_DIR]   (default: this script's directory)
File names are EXPECTED__stitch_DESCRIPTION.obj, EXPECTED the word `microdex-bench knot`
prints; bad__stitch_*.obj are malformed on purpose.
"""
import math
import os
import random
import sys

RNG = random.Random(20261125)


def add(p, q, s=1.0):
    return (p[0] + s * q[0], p[1] + s * q[1], p[2] + s * q[2])


def sub(p, q):
    return (p[0] - q[0], p[1] - q[1], p[2] - q[2])


def norm(p):
    return math.sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2])


def scale(p, s):
    return (s * p[0], s * p[1], s * p[2])


def unit(p):
    return scale(p, 1.0 / norm(p))


def cross(p, q):
    return (p[1] * q[2] - p[2] * q[1], p[2] * q[0] - p[0] * q[2], p[0] * q[1] - p[1] * q[0])


def bezier(p0, p1, p2, p3, n):
    out = []
    for k in range(1, n + 1):
        t = k / n
        s = 1 - t
        out.append(tuple(s**3 * p0[i] + 3 * s * s * t * p1[i] + 3 * s * t * t * p2[i] + t**3 * p3[i]
                         for i in range(3)))
    return out


def resample(curve, spacing):
    seg = [norm(sub(curve[i + 1], curve[i])) for i in range(len(curve) - 1)]
    total = sum(seg)
    n = max(1, round(total / spacing))
    h = total / n
    out, i, s_i = [], 0, 0.0
    for k in range(n + 1):
        s = min(k * h, total)
        while i + 2 < len(curve) and s_i + seg[i] < s:
            s_i += seg[i]
            i += 1
        t = min(1.0, max(0.0, (s - s_i) / seg[i])) if seg[i] > 0 else 0.0
        out.append(add(curve[i], sub(curve[i + 1], curve[i]), t))
    return out


def stitch_knot(throws, hitch, d=3e-5, width=10.0, depth=4.0, tightness=0.7, tail=40.0,
                tails=((math.pi, 0.2), (0.0, 0.2)), tilt=0.0, tilt_azimuth=0.0, post=1,
                mirror=False):
    """throws: [(hand, turns)]; lengths in thread diameters d; returns metres."""
    loose = 1.0 - tightness
    r_pair, p_pair = 0.68 + 0.6 * loose, 2.8 + 3.0 * loose
    r_wound, p_wound = 1.2 + 0.6 * loose, 2.2 + 2.5 * loose
    gap = 2.5 + 5.5 * loose
    ra = rb = r_pair
    if hitch:
        ra, rb = (0.0, r_wound) if post == 1 else (r_wound, 0.0)
    pitch = p_wound if hitch else p_pair
    a = (math.sin(tilt) * math.cos(tilt_azimuth), math.sin(tilt) * math.sin(tilt_azimuth),
         math.cos(tilt))
    u = unit(sub((1.0, 0.0, 0.0), scale(a, a[0])))
    v = cross(a, u)
    base = (0.0, 0.0, max(ra, rb) + 1.5)
    segments = [(1.5, 0.0)]
    for k, (hand, turns) in enumerate(throws):
        segments.append((turns * pitch, 2 * math.pi * hand * turns))
        if k + 1 < len(throws):
            segments.append((gap, 0.0))
    segments.append((1.0, 0.0))

    def radial(phi):
        return add(scale(u, math.cos(phi)), v, math.sin(phi))

    knot_a, knot_b = [], []
    tau = phi = 0.0

    def emit(t, f):
        knot_a.append(add(add(base, a, t), radial(f), -ra))
        knot_b.append(add(add(base, a, t), radial(f), rb))

    emit(0.0, 0.0)
    for length, dphi in segments:
        n = max(1, math.ceil(length * 8))
        for k in range(1, n + 1):
            emit(tau + length * k / n, phi + dphi * k / n)
        tau += length
        phi += dphi

    def leg(p, q):
        c = 0.4 * norm(sub(q, p))
        q1 = add(q, a, -c)
        q1 = (q1[0], q1[1], max(q1[2], 0.5))
        return [p] + bezier(p, add(p, (0, 0, c)), q1, q, 64)[:-1]

    def tail_of(p, out_sign, rise, azimuth, elevation):
        direction = (math.cos(elevation) * math.cos(azimuth),
                     math.cos(elevation) * math.sin(azimuth), math.sin(elevation))
        q1 = add(p, a, rise)
        q2 = add(q1, radial(phi), 2.0 * out_sign)
        q3 = add(q2, direction, 2.0)
        return bezier(p, q1, q2, q3, 48) + [add(q3, direction, tail)]

    strand_a = leg((-width / 2, 0.0, 0.0), knot_a[0]) + knot_a + tail_of(knot_a[-1], -1, 2.0,
                                                                          *tails[0])
    strand_b = leg((width / 2, 0.0, 0.0), knot_b[0]) + knot_b + tail_of(knot_b[-1], 1, 4.0,
                                                                         *tails[1])
    stitch = [(-width / 2 * math.cos(math.pi * k / 96), 0.0, -depth * math.sin(math.pi * k / 96))
              for k in range(1, 96)]
    curve = resample(strand_a[::-1] + stitch + strand_b, 1.0)
    if mirror:
        curve = [(x, -y, z) for x, y, z in curve]
    return [scale(p, d) for p in curve], d


def strands(curve):
    first = next(i for i, p in enumerate(curve) if p[2] < 0)
    last = max(i for i, p in enumerate(curve) if p[2] < 0)
    return curve[:first][::-1], curve[last + 1:]


def side_view_signs(a, b):
    """Crossing signs between a and b seen from +y (right = -x, up = z, over = larger y)."""
    def c2(p, q):
        return p[0] * q[1] - p[1] * q[0]
    signs = []
    for i in range(len(a) - 1):
        p = (-a[i][0], a[i][2])
        r = (-a[i + 1][0] - p[0], a[i + 1][2] - p[1])
        for j in range(len(b) - 1):
            q = (-b[j][0], b[j][2])
            s = (-b[j + 1][0] - q[0], b[j + 1][2] - q[1])
            den = c2(r, s)
            if den == 0:
                continue
            qp = (q[0] - p[0], q[1] - p[1])
            t, w = c2(qp, s) / den, c2(qp, r) / den
            if not (0 <= t < 1 and 0 <= w < 1):
                continue
            ya = a[i][1] + t * (a[i + 1][1] - a[i][1])
            yb = b[j][1] + w * (b[j + 1][1] - b[j][1])
            over, under = (r, s) if ya > yb else (s, r)
            signs.append(1 if c2(over, under) > 0 else -1)
    return signs


def check(throws, hitch, mirror):
    """Hands of an upright copy by brute force: two crossings per turn, in order."""
    curve, _ = stitch_knot(throws, hitch, mirror=mirror)
    h = -1 if mirror else 1
    expected = [h * hand for hand, turns in throws for _ in range(2 * turns)]
    found = side_view_signs(*strands(curve))
    assert found == expected, (throws, hitch, mirror, found, expected)


def clearance(curve, d):
    s = [0.0]
    for i in range(1, len(curve)):
        s.append(s[-1] + norm(sub(curve[i], curve[i - 1])))
    best = math.inf
    for i in range(len(curve)):
        for j in range(i + 1, len(curve)):
            if s[j] - s[i] > 3 * d:
                best = min(best, norm(sub(curve[i], curve[j])))
    return best / d


def place(curve, d, noise=0.1):
    """Turn about z, move in xy, add uniform noise of +-noise diameters."""
    angle = RNG.uniform(-math.pi, math.pi)
    c, s = math.cos(angle), math.sin(angle)
    dx, dy = RNG.uniform(-0.01, 0.01), RNG.uniform(-0.01, 0.01)
    out = []
    for x, y, z in curve:
        p = (c * x - s * y + dx, s * x + c * y + dy, z)
        out.append(tuple(p[i] + noise * d * RNG.uniform(-1, 1) for i in range(3)))
    return out


def write_obj(path, nodes, comment):
    with open(path, "w") as f:
        f.write("# %s\n# generated by generate_stitch_knots.py; units: metres; tissue z = 0\n"
                % comment)
        for p in nodes:
            f.write("v %.9g %.9g %.9g\n" % p)
        f.write("l " + " ".join(str(i + 1) for i in range(len(nodes))) + "\n")


SQUARE = [(1, 1), (-1, 1)]
GRANNY = [(1, 1), (1, 1)]
SURGEONS = [(1, 2), (-1, 1)]

CASES = [
    ("none__stitch.obj", [], False, {}, "stitch, strands untwisted"),
    ("square__stitch_tight.obj", SQUARE, False, {"tightness": 1.0}, "square, tight"),
    ("square__stitch_loose_tilted.obj", SQUARE, False,
     {"tightness": 0.1, "tilt": 0.9, "tilt_azimuth": 2.0, "mirror": True,
      "tails": ((2.5, 0.6), (-0.5, 1.0))}, "square, loose, leaning, mirrored"),
    ("granny__stitch.obj", GRANNY, False, {"tail": 120.0}, "granny, long tails"),
    ("granny__stitch_mirror.obj", GRANNY, False,
     {"mirror": True, "width": 25.0, "depth": 12.0, "tails": ((1.6, 0.3), (1.2, 0.9))},
     "granny, mirrored, wide deep stitch, tails to one side"),
    ("surgeons__stitch.obj", SURGEONS, False, {"tilt": 0.5}, "surgeon's"),
    ("slip__stitch.obj", SQUARE, True, {"post": 2}, "slip: two opposite half hitches (capsized square)"),
    ("slip__stitch_clove.obj", GRANNY, True, {"mirror": True},
     "slip: two half hitches of one sense (capsized granny)"),
    ("half-hitch__stitch.obj", [(1, 1)], True, {"tightness": 0.3}, "half hitch"),
    ("unknown__stitch_single_throw.obj", [(1, 1)], False, {}, "a lone throw"),
    ("unknown__stitch_three_throws.obj", [(1, 1), (-1, 1), (1, 1)], False, {},
     "three throws"),
]


def main():
    out_dir = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
    for throws in (SQUARE, GRANNY, SURGEONS, [(1, 1)]):
        for mirror in (False, True):
            check(throws, False, mirror)
            if len(throws) == 1:
                check(throws, True, mirror)
    for name, throws, hitch, kwargs, comment in CASES:
        curve, d = stitch_knot(throws, hitch, **kwargs)
        gap = clearance(curve, d)
        assert gap >= 1.0, (name, gap)
        nodes = place(curve, d)
        assert nodes[0][2] > 0 and nodes[-1][2] > 0, name
        write_obj(os.path.join(out_dir, name), nodes, comment)
    # Bad input: too few nodes for a stitch, and a malformed vertex in a stitch file.
    with open(os.path.join(out_dir, "bad__stitch_short.obj"), "w") as f:
        f.write("# a thread through the tissue with three nodes\n"
                "v 0 0 1e-4\nv 1e-4 0 -1e-4\nv 2e-4 0 1e-4\nl 1 2 3\n")
    with open(os.path.join(out_dir, "bad__stitch_vertex.obj"), "w") as f:
        f.write("# a stitch whose fourth vertex has two coordinates\n"
                "v 0 0 1e-4\nv 1e-4 0 -1e-4\nv 2e-4 0 -1e-4\nv 3e-4 0\nv 4e-4 0 1e-4\n"
                "l 1 2 3 4 5\n")


if __name__ == "__main__":
    main()
