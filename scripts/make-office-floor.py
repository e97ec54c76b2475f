#!/usr/bin/env python3
# A cluttered office floor for pex-sim, to try the whole set on a building
# that is not in worlds/ (docs/exploration.md, "Buildings not in worlds/").
#   scripts/make-office-floor.py [--glass] SEED OUT.wkt [WIDTH_M]
# 64 x 34 m by default: a row of rooms each side of a 2 m corridor along the
# south, an open plan (pillars, desk clusters with chairs) reached from that
# corridor by one 2 m passage through the rooms, a corridor and a row of rooms
# along the north. Rooms 3.5-6.5 m wide with 0.85-1 m doors, some joined by
# inner doors; desks against the far wall, a chair (four 5 cm legs) before
# each, cabinets. The same seed gives the same file. Nothing is checked
# here: a desk cluster may stand close before the passage (seed 7: a chair
# 0.66 m from its corner), as furniture does.
# --glass makes the rooms' corridor fronts (the walls holding their doors)
# and the open plan's meeting room glass panes (GLASS in the world file: the
# simulated laser sees them only near their normal); the layout is the same
# as without it.
import random, sys
args=[a for a in sys.argv[1:] if a!="--glass"]; glass="--glass" in sys.argv[1:]
seed=int(args[0]); out=args[1]
W=float(args[2]) if len(args)>2 else 64.0
R=random.Random(seed)
walls=[]; polys=[]
glass_now=False  # walls added while True are glass (with --glass)
def wall(x1,y1,x2,y2): walls.append(((x1,y1),(x2,y2),glass and glass_now))
def rect(x,y,w,h): polys.append([(x,y),(x+w,y),(x+w,y+h),(x,y+h)])
def wall_with_doors(along_x,c,a0,a1,doors):
    """A wall at x or y = c from a0 to a1 (along x if along_x), with gaps
    for doors: a list of (centre, width)."""
    def piece(a,b): wall(a,c,b,c) if along_x else wall(c,a,c,b)
    at=a0
    for d,w in sorted(doors):
        a,b=d-w/2,d+w/2
        if a>at+0.01: piece(at,a)
        at=b
    if a1>at+0.01: piece(at,a1)
def hwall_with_doors(y,x1,x2,doors): wall_with_doors(True,y,x1,x2,doors)
def vwall_with_doors(x,y1,y2,doors): wall_with_doors(False,x,y1,y2,doors)
def chair(cx,cy):
    for dx in (-0.22,0.22):
        for dy in (-0.22,0.22): rect(cx+dx-0.025,cy+dy-0.025,0.05,0.05)
def door_w(): return R.choice([0.85,0.9,0.9,1.0])
# Bands in y: south rooms 0-6, corridor 6-8, rooms 8-14, open plan 14-26,
# corridor 26-28, north rooms 28-34.
H=34.0
wall(0,0,W,0); wall(W,0,W,H); wall(W,H,0,H); wall(0,H,0,0)
def room_row(y0,y1,door_y,desk_side,extra=(),keep=None):
    x=0.0; cuts=[0.0]
    while x<W-7:
        x+=R.uniform(3.5,6.5); cuts.append(x)
    cuts[-1]=W
    doors=[]
    for i in range(len(cuts)-1):
        a,b=cuts[i],cuts[i+1]
        if i>0:  # partition wall, sometimes an inner door
            if R.random()<0.25: vwall_with_doors(a,y0,y1,[((y0+y1)/2,0.9)])
            else: wall(a,y0,a,y1)
        dc=R.uniform(a+0.8,b-0.8); doors.append((dc,door_w()))
        # furniture: desks along the far wall, chairs, a cabinet on a side wall
        far=y1 if desk_side>0 else y0
        n=int((b-a-0.4)//1.7)
        for k in range(n):
            dx=a+0.25+k*1.7
            if keep and dx+1.6>keep[0]-0.5 and dx<keep[1]+0.5: continue
            if R.random()<0.8:
                if desk_side>0: rect(dx,far-0.85,1.6,0.8); chair(dx+0.8,far-1.45)
                else: rect(dx,far+0.05,1.6,0.8); chair(dx+0.8,far+1.45)
        if R.random()<0.6:
            cx=a+0.05 if R.random()<0.5 else b-0.55
            if keep and cx+0.5>keep[0]-0.3 and cx<keep[1]+0.3: continue
            cy=(y0+y1)/2-0.6
            rect(cx,cy,0.5,1.2)
    doors=[d for d in doors if not (keep and abs(d[0]-(keep[0]+keep[1])/2)<(keep[1]-keep[0])/2+d[1]/2+0.3)]
    global glass_now
    glass_now=True
    hwall_with_doors(door_y,0,W,doors+list(extra))
    glass_now=False
room_row(0,6,6,-1)     # south rooms: doors on y=6, desks against y=0
# The rooms north of the corridor, doors on y=8; the passage x 30-32 runs
# through them to the open plan (no furniture or door in it).
room_row(8,14,8,+1,extra=[(31.0,2.0)],keep=(30.0,32.0))
hwall_with_doors(14,0,W,[(31.0,2.0)])
wall(30,8,30,14); wall(32,8,32,14)
# open plan 14-26: pillars on an 8 m grid, desk clusters with chairs
for px in range(8,int(W),8):
    for py in (18.0,22.0):
        rect(px-0.2,py-0.2,0.4,0.4)
x=2.0
while x<W-5:
    if R.random()<0.75:
        y=R.choice([15.5,19.6,23.0])
        rect(x,y,3.2,1.6)
        for k in (0.8,2.4): chair(x+k,y-0.6); chair(x+k,y+2.2)
    x+=R.uniform(4.5,6.5)
# a meeting room in the open plan, one door
mx=R.uniform(36,W-10)
glass_now=True
wall(mx,17,mx+6,17); wall(mx+6,17,mx+6,23); wall(mx,23,mx+6,23); vwall_with_doors(mx,17,23,[(20,1.0)])
glass_now=False
rect(mx+1.5,19.2,3.0,1.6)
# the open plan's north wall, three openings onto the north corridor
hwall_with_doors(26,0,W,[(6,1.8),(W/2,1.8),(W-6,1.8)])
room_row(28,34,28,+1)  # north rooms: doors on y=28, desks against y=34
f=open(out,'w')
f.write("# office floor from scripts/make-office-floor.py%s, seed %d, %.0f x %.0f m\n"%(" --glass" if glass else "",seed,W,H))
for (a,b,g) in walls: f.write("%sLINESTRING (%.3f %.3f, %.3f %.3f)\n"%("GLASS " if g else "",a[0],a[1],b[0],b[1]))
for p in polys: f.write("POLYGON ((%s))\n"%", ".join("%.3f %.3f"%q for q in p+[p[0]]))
f.write("START 1.5 7.0 0.0\n")
print(len(walls),"walls (%d glass)"%sum(1 for w in walls if w[2]),len(polys),"polygons")
