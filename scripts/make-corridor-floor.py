#!/usr/bin/env python3
# A long office floor for pex-sim, to try the whole set on a building that is
# not in worlds/ (docs/exploration.md, "Walled bays": floor90 and floor120).
#   scripts/make-corridor-floor.py SEED LENGTH_M [BANDS] > OUT.wkt
# floor90 is `7 90`, floor120 `11 120`. Each band is a 2 m corridor along x
# with a row of rooms 9 m deep on each side (the first row and the last are
# 10 m, to the outer walls); rooms 4-8 m wide, one door of 0.85-1.2 m each
# onto the corridor, 30 % of the walls between rooms with an inner door of
# 0.9 m. Furniture: up to two desks (1.6 x 0.8 m) 5 cm off each room's far
# wall with a chair of four 4 cm legs in front, a cabinet (0.6 x 1.2 m)
# against a side wall in half the rooms, a bench (1.2 x 0.4 m) every 25 m
# of corridor against its far side. The robot starts at the first corridor's
# west end, facing east. The same arguments give the same file; nothing is
# checked here (a bench may stand before a door and shut its room, as it
# does on floor120: the robot sees in through the slit and lists the room
# behind a gap narrower than it).
# With BANDS > 1 the bands are stacked in y with nothing joining their
# corridors: only the first is reachable.
import random
import sys


def main():
    if len(sys.argv) not in (3, 4):
        sys.exit("usage: make-corridor-floor.py SEED LENGTH_M [BANDS] > OUT.wkt")
    seed, length = int(sys.argv[1]), float(sys.argv[2])
    bands = int(sys.argv[3]) if len(sys.argv) == 4 else 1
    if length < 10.0 or bands < 1:
        sys.exit("make-corridor-floor.py: LENGTH_M must be at least 10 and BANDS at least 1")
    rnd = random.Random(seed)
    width = 2.0 + bands * 20.0
    lines = [[(0, 0), (length, 0), (length, width), (0, width), (0, 0)]]
    boxes = []

    def box(x, y, w, h):
        boxes.append([(x, y), (x + w, y), (x + w, y + h), (x, y + h), (x, y)])

    start = None
    # The random draws stay in this order: the floors in docs/ are these seeds.
    for band in range(bands):
        y0 = band * 20.0 + 1.0
        corridor_y0, corridor_y1 = y0 + 9.0, y0 + 11.0
        if start is None:
            start = (1.0, corridor_y0 + 1.0)
        rows = [(corridor_y0, max(y0 - 1.0, 0.0), corridor_y0),
                (corridor_y1, corridor_y1, corridor_y1 + 9.0 if band < bands - 1 else width)]
        for side, (wall_y, room_y0, room_y1) in enumerate(rows):
            room_y1 = min(room_y1, width)
            xs, x = [0.0], 0.0
            while True:
                x += rnd.uniform(4.0, 8.0)
                if x > length - 3.0:
                    break
                xs.append(round(x, 2))
            xs.append(length)
            far_y = room_y0 if side == 0 else room_y1
            for i in range(len(xs) - 1):
                a, b = xs[i], xs[i + 1]
                # The corridor wall with the room's door.
                door_w = rnd.uniform(0.85, 1.2)
                door_x = rnd.uniform(a + 0.4, b - 0.4 - door_w)
                lines.append([(a, wall_y), (door_x, wall_y)])
                lines.append([(door_x + door_w, wall_y), (b, wall_y)])
                # The wall to the room before, with an inner door or not.
                if i > 0:
                    if rnd.random() < 0.3:
                        inner_y = rnd.uniform(room_y0 + 0.5, room_y1 - 1.5)
                        lines.append([(a, room_y0), (a, inner_y)])
                        lines.append([(a, inner_y + 0.9), (a, room_y1)])
                    else:
                        lines.append([(a, room_y0), (a, room_y1)])
                for _ in range(rnd.randint(0, 2)):
                    w, h = 1.6, 0.8
                    desk_x = rnd.uniform(a + 0.3, b - 0.3 - w)
                    desk_y = far_y + 0.05 if side == 0 else far_y - 0.05 - h
                    box(round(desk_x, 2), round(desk_y, 2), w, h)
                    chair_x = desk_x + w / 2
                    chair_y = desk_y + h + 0.5 if side == 0 else desk_y - 0.5
                    for lx, ly in [(-0.22, -0.22), (0.2, -0.22), (-0.22, 0.2), (0.2, 0.2)]:
                        box(round(chair_x + lx, 2), round(chair_y + ly, 2), 0.04, 0.04)
                if rnd.random() < 0.5:
                    cabinet_x = a + 0.05 if rnd.random() < 0.5 else b - 0.65
                    cabinet_y = rnd.uniform(room_y0 + 1.0, room_y1 - 2.5)
                    box(round(cabinet_x, 2), round(cabinet_y, 2), 0.6, 1.2)
        for _ in range(int(length / 25)):
            box(round(rnd.uniform(5, length - 5), 2), corridor_y1 - 0.45, 1.2, 0.4)

    out = [f"# throwaway office floor seed {seed}, {length} x {width} m, {bands} corridor(s)",
           f"START {start[0]} {start[1]} 0.0"]
    out += ["LINESTRING(" + ", ".join(f"{x:g} {y:g}" for x, y in line) + ")" for line in lines]
    out += ["POLYGON((" + ", ".join(f"{x:g} {y:g}" for x, y in b) + "))" for b in boxes]
    print("\n".join(out))


main()
