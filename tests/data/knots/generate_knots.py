#!/usr/bin/env python3
"""Writes the reference thread polylines of tests/data/knots (OBJ, one `l` element).

Pure Python, independent of the C++ code: the curves are parametrised here again, the
handedness of every chiral reference is checked by a brute-force count of the crossing
signs of its projection on the xy plane, and each thread is rotated, translated, scaled to
a 30 um thread (nodes one diameter apart) and given noise of 1 % of the diameter.

Usage: python3 generate_knots.py [OUTPUT_DIR]   (default: this script's directory)
File names are EXPECTED__DESCRIPTION.obj, EXPECTED the word `microdex-bench knot` prints.
"""
import math
import os
import random
import sys

DIAMETER_M = 3e-5
RNG = random.Random(20261121)


def torus(p, q, n, mirror=False):
    # Positive crossings seen from +z unless mirrored (checked below).
    zs = 1.0 if mirror else -1.0
    return [((2 + math.cos(q * s)) * math.cos(p * s), (2 + math.cos(q * s)) * math.sin(p * s),
             zs * math.sin(q * s)) for s in (2 * math.pi * k / n for k in range(n))]


def figure_eight(n):
    return [((2 + math.cos(2 * s)) * math.cos(3 * s), (2 + math.cos(2 * s)) * math.sin(3 * s),
             math.sin(4 * s)) for s in (2 * math.pi * k / n for k in range(n))]


def braid(strands, word, per=24):
    """Closure of a braid around the z axis; +i: the outward strand passes over."""
    g = len(word)
    at_slot = list(range(strands))
    pieces = [[] for _ in range(strands)]
    for k, w in enumerate(word):
        lo = abs(w) - 1
        for step in range(per):
            u = (step + 0.5) / per
            phi = 2 * math.pi * (k + u) / g
            sm = u * u * (3 - 2 * u)
            for slot in range(strands):
                r, z = 3.0 + slot, 0.0
                if slot in (lo, lo + 1):
                    outward = slot == lo
                    r = 3.0 + lo + (sm if outward else 1 - sm)
                    over = outward == (w > 0)
                    z = (0.35 if over else -0.35) * math.sin(math.pi * u)
                pieces[at_slot[slot]].append((r * math.cos(phi), r * math.sin(phi), z))
        at_slot[lo], at_slot[lo + 1] = at_slot[lo + 1], at_slot[lo]
    end_slot = {s: slot for slot, s in enumerate(at_slot)}
    curve, s = [], 0
    for _ in range(strands):
        curve += pieces[s]
        s = end_slot[s]
        if s == 0:
            break
    return curve


def overhand_tied(passes, right):
    """Loop crossing the standing part, the end through the loop `passes` times."""
    lz = 0.3 if right else -0.3
    h = -1.0 if right else 1.0
    c = [(x / 4.0, 0.0, 0.0) for x in range(-24, 8)]
    c += [(2.0, 0.0, 0.0), (2.6, 1.2, 0.0), (2.0, 2.6, 0.0), (0.5, 3.2, 0.0), (-1.0, 3.1, 0.0),
          (-2.0, 2.4, 0.0), (-2.2, 1.2, 0.0), (-2.1, 0.4, lz / 2), (-2.1, 0.1, lz),
          (-2.1, -0.2, lz), (-2.1, -0.5, lz / 2), (-1.9, -1.2, 0.0), (-1.5, -0.9, 0.0)]
    m = 48 * passes
    for k in range(m + 1):
        t = 2 * math.pi * passes * k / m + 0.05
        c.append((-1.0 + 2.0 * k / m, -0.6 * math.cos(t), h * 0.6 * math.sin(t)))
    c += [(1.5, -0.9, 0.0), (2.2, -1.6, 0.0), (3.5, -2.0, 0.0)]
    c += [(x / 4.0, -2.0, 0.0) for x in range(16, 33)]
    return c


def long_knot(closed, tail):
    """Opened at the node of largest x; one tail over the top to the left, one to the right."""
    n = len(closed)
    i = max(range(n), key=lambda k: closed[k][0])
    xs = [p[0] for p in closed]
    zs = [p[2] for p in closed]
    size = max(max(xs) - min(xs), max(p[1] for p in closed) - min(p[1] for p in closed),
               max(zs) - min(zs))
    xr, xl, zt = max(xs) + 0.3 * size, min(xs) - 0.3 * size, max(zs) + 0.3 * size
    a, b = closed[(i + 1) % n], closed[(i - 1) % n]
    c = [(xl - tail, a[1], zt), (xl, a[1], zt), (xr, a[1], zt), (xr, a[1], a[2])]
    c += [closed[(i + k) % n] for k in range(1, n)]
    c += [(xr, b[1], b[2]), (xr + tail, b[1], b[2])]
    return c


def splice(a, b, gap=2.0):
    ax = max(p[0] for p in a)
    bx = min(p[0] for p in b)
    dx = max(a[-1][0] + gap - b[0][0], ax + gap - bx)
    shift = (dx, a[-1][1] - b[0][1], a[-1][2] - b[0][2])
    return a + [(p[0] + shift[0], p[1] + shift[1], p[2] + shift[2]) for p in b]


def coil(turns, radius, pitch, per):
    return [(radius * math.cos(2 * math.pi * k / per), radius * math.sin(2 * math.pi * k / per),
             pitch * k / per) for k in range(turns * per + 1)]


def ascending_walk(steps, step, rise, seed):
    """Planar random walk rising along the thread: an unknot however it crosses itself."""
    r = random.Random(seed)
    x = y = z = heading = 0.0
    c = [(0.0, 0.0, -5 * step), (0.0, 0.0, 0.0)]
    for _ in range(steps):
        heading += r.gauss(0.0, 0.6)
        if math.hypot(x, y) > 0.45 * step * math.sqrt(steps):
            heading = math.atan2(-y, -x)
        x, y, z = x + step * math.cos(heading), y + step * math.sin(heading), z + rise
        c.append((x, y, z))
    c.append((x, y, z + 5 * step))
    return c


def resample(open_curve, spacing):
    seg = [math.dist(open_curve[i], open_curve[i + 1]) for i in range(len(open_curve) - 1)]
    total = sum(seg)
    n = max(1, round(total / spacing))
    out, i, s0 = [], 0, 0.0
    for k in range(n + 1):
        s = min(k * total / n, total)
        while i < len(seg) - 1 and s0 + seg[i] < s:
            s0 += seg[i]
            i += 1
        t = 0.0 if seg[i] == 0 else min(1.0, max(0.0, (s - s0) / seg[i]))
        a, b = open_curve[i], open_curve[i + 1]
        out.append(tuple(a[j] + t * (b[j] - a[j]) for j in range(3)))
    return out


def crossing_signs(curve, closed):
    """Signs of the crossings of the xy projection (right-hand rule), by brute force."""
    n = len(curve)
    m = n if closed else n - 1
    signs = []

    def orient(u, v, w):
        return (v[0] - u[0]) * (w[1] - u[1]) - (v[1] - u[1]) * (w[0] - u[0])

    for i in range(m):
        a, b = curve[i], curve[(i + 1) % n]
        for j in range(i + 2, m):
            if closed and i == 0 and j == n - 1:
                continue
            p, q = curve[j], curve[(j + 1) % n]
            o1, o2, o3, o4 = orient(a, b, p), orient(a, b, q), orient(p, q, a), orient(p, q, b)
            if o1 * o2 >= 0 or o3 * o4 >= 0:
                continue
            t, s = o3 / (o3 - o4), o1 / (o1 - o2)
            za, zp = a[2] + t * (b[2] - a[2]), p[2] + s * (q[2] - p[2])
            dab, dpq = (b[0] - a[0], b[1] - a[1]), (q[0] - p[0], q[1] - p[1])
            over, under = (dab, dpq) if za > zp else (dpq, dab)
            signs.append(1 if over[0] * under[1] - over[1] * under[0] > 0 else -1)
    return signs


def check_signs(curve, closed, sign, count):
    signs = crossing_signs(curve, closed)
    assert signs == [sign] * count, (signs, sign, count)


def to_thread(curve, spacing):
    """Resampled one diameter apart, scaled to metres, moved rigidly, 1 % noise."""
    pts = resample(curve, spacing)
    qw, qx, qy, qz = (RNG.gauss(0, 1) for _ in range(4))
    norm = math.sqrt(qw * qw + qx * qx + qy * qy + qz * qz)
    qw, qx, qy, qz = qw / norm, qx / norm, qy / norm, qz / norm
    rot = [[1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)],
           [2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)],
           [2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)]]
    origin = [RNG.uniform(-0.01, 0.01) for _ in range(3)]
    scale = DIAMETER_M / spacing
    out = []
    for p in pts:
        q = [scale * sum(rot[r][c] * p[c] for c in range(3)) + origin[r] for r in range(3)]
        out.append([v + RNG.uniform(-0.01, 0.01) * DIAMETER_M for v in q])
    return out


def write_obj(path, nodes, comment):
    with open(path, "w") as f:
        f.write(f"# {comment}\n# generated by generate_knots.py; units: metres\n")
        for p in nodes:
            f.write("v %.9g %.9g %.9g\n" % tuple(p))
        f.write("l " + " ".join(str(i + 1) for i in range(len(nodes))) + "\n")


def tight_tails(closed):
    """Trefoil whose tails stop a few nodes out of the knot and hook in random directions."""
    body = long_knot(closed, 0.0)[4:-2]
    d = 0.1
    head, tail = [], []
    for end, out in ((body[0], head), (body[-1], tail)):
        v = [RNG.gauss(0, 1) for _ in range(3)]
        n = math.sqrt(sum(c * c for c in v))
        out += [tuple(end[j] + k * d * v[j] / n for j in range(3)) for k in (1, 2)]
    return list(reversed(head)) + body + tail


def main():
    out_dir = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
    right, left = torus(2, 3, 400), torus(2, 3, 400, mirror=True)
    check_signs(right, True, 1, 3)
    check_signs(left, True, -1, 3)
    five = torus(2, 5, 500)
    check_signs(five, True, 1, 5)
    tied2 = overhand_tied(2, right=False)
    check_signs(tied2, False, -1, 5)
    tied1r, tied1l = overhand_tied(1, True), overhand_tied(1, False)
    check_signs(tied1r, False, 1, 3)
    check_signs(tied1l, False, -1, 3)
    cases = [
        ("overhand-right__torus", long_knot(right, 3.0), "right-handed trefoil T(2,3)"),
        ("overhand-left__torus", long_knot(left, 3.0), "left-handed trefoil"),
        ("overhand-right__tight_tails", tight_tails(right),
         "right-handed trefoil, short tails hooked in random directions"),
        ("double-overhand__torus", long_knot(five, 3.0), "cinquefoil T(2,5)"),
        ("double-overhand__tied", tied2, "left double overhand as tied: end twice through loop"),
        ("figure-eight__lissajous", long_knot(figure_eight(400), 3.0), "figure-eight 4_1"),
        ("square__spliced", splice(tied1r, tied1l), "right overhand + left overhand"),
        ("granny__spliced", splice(long_knot(left, 3.0), long_knot(left, 3.0)),
         "left trefoil + left trefoil"),
        ("surgeons__spliced", splice(overhand_tied(2, True), tied1l),
         "right double overhand + left overhand"),
        ("none__coil", coil(12, 1.0, 0.4, 40), "coil of 12 turns"),
        ("none__messy", ascending_walk(400, 0.5, 0.02, 5), "ascending random walk"),
        ("unknown__three_twist", long_knot(braid(3, [1, 1, 1, 2, -1, 2]), 3.0),
         "three-twist knot 5_2 (not in the classified set)"),
    ]
    for name, curve, comment in cases:
        write_obj(os.path.join(out_dir, name + ".obj"), to_thread(curve, 0.1), comment)
    with open(os.path.join(out_dir, "bad__vertex.obj"), "w") as f:
        f.write("# malformed vertex on line 3\nv 0 0 0\nv 1 zero 0\nv 2 0 0\nl 1 2 3\n")
    with open(os.path.join(out_dir, "bad__index.obj"), "w") as f:
        f.write("# index out of range on line 6\nv 0 0 0\nv 1 0 0\nv 2 0 0\n\nl 1 2 3 4\n")
    with open(os.path.join(out_dir, "bad__no_line.obj"), "w") as f:
        f.write("# vertices but no l element\nv 0 0 0\nv 1 0 0\n")


if __name__ == "__main__":
    main()
