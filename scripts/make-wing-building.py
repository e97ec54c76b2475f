#!/usr/bin/env python3
# A building of wings for pex-sim, to try the whole set on a layout family the
# shipped worlds and scripts/make-office-floor.py do not have (docs/
# exploration.md, "Sessions 53–54: buildings of wings").
#   scripts/make-wing-building.py [--glass] SHAPE SEED OUT.wkt
# SHAPE: L, T, U or ring (four wings round a closed core: a corridor loop).
# Each wing is a corridor 1.8-2.6 m wide with a row of rooms 4.5-7 m deep on
# each side, 3-7.5 m wide, one 0.85-1 m door onto the corridor each (a few
# rooms a 2-3 m opening: a lounge; a quarter of the walls between rooms an
# inner door); wings 30-60 m long, joined where their corridors cross; desks
# with chairs against the far walls, cabinets, a meeting table in wide rooms,
# 600-3000 m² of floor. The same arguments
# give the same file. With --glass the rooms' corridor fronts are glass panes
# (GLASS in the world file). Nothing is checked here but that START is in a
# corridor: a chair may stand close before a door, as furniture does.
#
# Drawn on a 5 cm grid of labels (outside, corridor, room k); a wall is every
# cell side between different labels but a door, merged into straight runs.
import random
import sys

args = [a for a in sys.argv[1:] if a != "--glass"]
glass = "--glass" in sys.argv[1:]
if len(args) != 3 or args[0] not in ("L", "T", "U", "ring"):
    sys.exit("usage: make-wing-building.py [--glass] L|T|U|ring SEED OUT.wkt")
shape, seed, out = args[0], int(args[1]), args[2]
R = random.Random("%s-%d" % (shape, seed))
RES = 0.05  # grid cell, m


def cells(m):
    return int(round(m / RES))


# Wings: (axis, fixed coordinate of the corridor's low side, from, to), in
# metres, before the grid. Corridor width and room depth are the building's.
cw = R.choice([1.8, 2.0, 2.2, 2.4, 2.6])
depth = R.uniform(4.5, 7.0)
band = depth + cw + depth  # a wing's width
la = R.uniform(40, 60)     # the first wing, along x
lb = R.uniform(25, 45)     # the others, along y
wings = [("x", depth, 0.0, la)]
if shape == "L":
    wings.append(("y", la - depth - cw, 0.0, band + lb))
elif shape == "T":
    xm = R.uniform(0.35, 0.65) * la
    wings.append(("y", xm, 0.0, band + lb))
elif shape == "U":
    wings.append(("y", depth, 0.0, band + lb))
    wings.append(("y", la - depth - cw, 0.0, band + lb))
else:  # ring: a second x wing closes the loop
    wings.append(("y", depth, 0.0, band + lb))
    wings.append(("y", la - depth - cw, 0.0, band + lb))
    wings.append(("x", band + lb - depth - cw, 0.0, la))
W = max(w[3] for w in wings if w[0] == "x")
H = max(w[3] for w in wings if w[0] == "y") if any(w[0] == "y" for w in wings) else band
NX, NY = cells(W) + 2, cells(H) + 2
OUT, CORR = -1, 0
lab = [[OUT] * NY for _ in range(NX)]


def fill(x0, y0, x1, y1, v, only=None):
    for i in range(max(0, cells(x0)), min(NX, cells(x1))):
        col = lab[i]
        for j in range(max(0, cells(y0)), min(NY, cells(y1))):
            if only is None or col[j] in only:
                col[j] = v


def free(x0, y0, x1, y1):
    for i in range(max(0, cells(x0)), min(NX, cells(x1))):
        for j in range(max(0, cells(y0)), min(NY, cells(y1))):
            if lab[i][j] != OUT:
                return False
    return True


# Corridors first, then rooms along them where the ground is still empty.
for ax, c, a0, a1 in wings:
    if ax == "x":
        fill(a0, c, a1, c + cw, CORR)
    else:
        fill(c, a0, c + cw, a1, CORR)
rooms = []  # (x0, y0, x1, y1, front side: 'N','S','E','W' toward the corridor)
for ax, c, a0, a1 in wings:
    for side in (-1, +1):
        a = a0
        while a < a1 - 2.5:
            w = min(R.uniform(3.0, 7.5), a1 - a)
            if a1 - (a + w) < 2.5:
                w = a1 - a
            if ax == "x":
                y0, y1 = (c - depth, c) if side < 0 else (c + cw, c + cw + depth)
                box, front = (a, y0, a + w, y1), ("N" if side < 0 else "S")
            else:
                x0, x1 = (c - depth, c) if side < 0 else (c + cw, c + cw + depth)
                box, front = (x0, a, x1, a + w), ("E" if side < 0 else "W")
            if box[0] >= -1e-9 and box[1] >= -1e-9 and free(*box):
                rooms.append(box + (front,))
                fill(*box[:4], len(rooms))
            a += w

walls_glass = set()  # unit edges that are glass
doors = set()        # unit edges left open


def open_run(vertical, k, m0, m1):
    """Leave the cell sides on grid line k (x = k if vertical, else y = k)
    from grid m0 to m1 open."""
    for m in range(m0, m1):
        doors.add((vertical, k, m))


def front_edges(r):
    """The grid line and range of a room's front (the side on the corridor)."""
    x0, y0, x1, y1, f = r
    if f in "NS":
        return False, cells(y1 if f == "N" else y0), cells(x0), cells(x1)
    return True, cells(x1 if f == "E" else x0), cells(y0), cells(y1)


furniture = []  # polygons


def rect(x, y, w, h):
    furniture.append([(x, y), (x + w, y), (x + w, y + h), (x, y + h)])


def chair(cx, cy):
    for dx in (-0.22, 0.22):
        for dy in (-0.22, 0.22):
            rect(cx + dx - 0.025, cy + dy - 0.025, 0.05, 0.05)


for k, r in enumerate(rooms):
    vertical, line, m0, m1 = front_edges(r)
    n = m1 - m0
    lounge = R.random() < 0.08 and n * RES > 4.0
    dw = cells(R.uniform(2.0, 3.0)) if lounge else cells(R.choice([0.85, 0.9, 0.9, 1.0]))
    lo, hi = m0 + cells(0.5), m1 - cells(0.5) - dw
    ok = []
    for s in range(lo, max(lo, hi) + 1):
        def corr(m):  # the cell beyond the front at m is corridor
            if vertical:
                i = line - 1 if r[4] == "W" else line
                return 0 <= i < NX and lab[i][m] == CORR
            j = line - 1 if r[4] == "S" else line
            return 0 <= j < NY and lab[m][j] == CORR
        if all(corr(m) for m in range(s, s + dw)):
            ok.append(s)
    if not ok:
        continue  # no corridor before it: reached through an inner door or not at all
    s = R.choice(ok)
    open_run(vertical, line, s, s + dw)
    # furniture: desks with chairs along the far wall, a cabinet, a table
    x0, y0, x1, y1, f = r
    if lounge:
        for q in range(R.randint(1, 3)):
            rect(R.uniform(x0 + 0.8, max(x0 + 0.8, x1 - 1.6)), R.uniform(y0 + 0.8, max(y0 + 0.8, y1 - 1.6)), 0.8, 0.8)
        continue
    if f in "NS":
        span, far = (x0, x1), (y0 if f == "N" else y1)
        nd = int((x1 - x0 - 0.4) // 1.7)
        for q in range(nd):
            if R.random() < 0.75:
                dx = x0 + 0.25 + q * 1.7
                if f == "N":
                    rect(dx, far + 0.05, 1.6, 0.8); chair(dx + 0.8, far + 1.45)
                else:
                    rect(dx, far - 0.85, 1.6, 0.8); chair(dx + 0.8, far - 1.45)
    else:
        far = x0 if f == "E" else x1
        nd = int((y1 - y0 - 0.4) // 1.7)
        for q in range(nd):
            if R.random() < 0.75:
                dy = y0 + 0.25 + q * 1.7
                if f == "E":
                    rect(far + 0.05, dy, 0.8, 1.6); chair(far + 1.45, dy + 0.8)
                else:
                    rect(far - 0.85, dy, 0.8, 1.6); chair(far - 1.45, dy + 0.8)
    if (x1 - x0) > 5.5 and (y1 - y0) > 5.5 and R.random() < 0.5:  # a meeting table
        cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
        rect(cx - 1.2, cy - 0.6, 2.4, 1.2)
        for dx in (-0.6, 0.6):
            chair(cx + dx, cy - 1.2); chair(cx + dx, cy + 1.2)
    if R.random() < 0.5:  # a cabinet against a side wall, away from the front
        if f in "NS":
            cy = (y0 + 0.3) if f == "S" else (y1 - 1.5)
            cx = x0 + 0.05 if R.random() < 0.5 else x1 - 0.55
            rect(cx, cy, 0.5, 1.2)
        else:
            cx = (x0 + 0.3) if f == "W" else (x1 - 1.5)
            cy = y0 + 0.05 if R.random() < 0.5 else y1 - 0.55
            rect(cx, cy, 1.2, 0.5)

# inner doors: a quarter of the walls between rooms along the same corridor
pairs = {}
for i in range(1, NX):
    for j in range(NY):
        a, b = lab[i - 1][j], lab[i][j]
        if a > 0 and b > 0 and a != b:
            pairs.setdefault((min(a, b), max(a, b), True, i), []).append(j)
for i in range(NX):
    for j in range(1, NY):
        a, b = lab[i][j - 1], lab[i][j]
        if a > 0 and b > 0 and a != b:
            pairs.setdefault((min(a, b), max(a, b), False, j), []).append(i)
for (a, b, vertical, line), ms in sorted(pairs.items()):
    ms.sort()
    if len(ms) * RES < 3.0 or R.random() >= 0.25:
        continue
    mid = ms[len(ms) // 2]
    open_run(vertical, line, mid - cells(0.45), mid + cells(0.45))

# walls: every cell side between different labels (or a labelled cell and
# the border) that is not a door, merged into runs
edges = {True: {}, False: {}}  # vertical? -> line -> list of m
for i in range(NX + 1):
    for j in range(NY):
        a = lab[i - 1][j] if i > 0 else OUT
        b = lab[i][j] if i < NX else OUT
        if a != b and (a != OUT or b != OUT) and (True, i, j) not in doors:
            edges[True].setdefault(i, []).append((j, glass and CORR in (a, b) and OUT not in (a, b)))
for j in range(NY + 1):
    for i in range(NX):
        a = lab[i][j - 1] if j > 0 else OUT
        b = lab[i][j] if j < NY else OUT
        if a != b and (a != OUT or b != OUT) and (False, j, i) not in doors:
            edges[False].setdefault(j, []).append((i, glass and CORR in (a, b) and OUT not in (a, b)))
lines = []
for vertical in (True, False):
    for k, ms in edges[vertical].items():
        ms.sort()
        start, prev, g = ms[0][0], ms[0][0], ms[0][1]
        for m, gm in ms[1:] + [(None, None)]:
            if m is not None and m == prev + 1 and gm == g:
                prev = m
                continue
            a, b = start * RES, (prev + 1) * RES
            kk = k * RES
            lines.append(((kk, a, kk, b) if vertical else (a, kk, b, kk), g))
            if m is not None:
                start, prev, g = m, m, gm

floor = sum(1 for col in lab for v in col if v != OUT) * RES * RES
sx, sy = wings[0][2] + 1.5, wings[0][1] + cw / 2
with open(out, "w") as f:
    f.write("# wing building from scripts/make-wing-building.py%s %s %d: %.0f x %.0f m, %.0f m2 of floor,"
            " corridor %.1f m, rooms %.1f m deep, %d rooms\n"
            % (" --glass" if glass else "", shape, seed, W, H, floor, cw, depth, len(rooms)))
    for (x0, y0, x1, y1), g in lines:
        f.write("%sLINESTRING (%.3f %.3f, %.3f %.3f)\n" % ("GLASS " if g else "", x0, y0, x1, y1))
    for p in furniture:
        f.write("POLYGON ((%s))\n" % ", ".join("%.3f %.3f" % q for q in p + [p[0]]))
    f.write("START %.2f %.2f 0.0\n" % (sx, sy))
print("%s %d: %.0f x %.0f m, %.0f m2, %d rooms, %d walls (%d glass), %d polygons"
      % (shape, seed, W, H, floor, len(rooms), len(lines), sum(1 for l in lines if l[1]), len(furniture)))
