"""An independent DXF producer and reference for tests/cli/test_dxf.sh: Debian's python3-ezdxf
writes one DXF per entity kind (every form curvestep draws exactly, in mm) and flattens each
through its own geometry (ezdxf.path.make_path(e).flattening(d), blocks through
ezdxf.disassemble.recursive_decompose). Then compares curvestep's chords with those polylines,
both ways: every vertex of each set must lie within TOL mm of the other set's polylines.

  dxf_ezdxf.py write DIR            writes DIR/<name>.dxf and DIR/<name>.ref for every case
  dxf_ezdxf.py compare REF OUT TOL  REF: the .ref polylines; OUT: `curvestep flatten` output;
                                    prints "max A->B, B->A" and exits 1 beyond TOL
"""
import math
import sys


def cases():
    """(name, function adding the entities to a fresh document's model space)."""
    def line(doc, msp):
        msp.add_line((0, 0), (10, 5))
        msp.add_line((3, -2, 7), (-4, 9, -1))  # 3-D: drawn from above

    def circle(doc, msp):
        msp.add_circle((20, 20), 5)
        msp.add_circle((-3, 4), 0.5)

    def arc(doc, msp):
        msp.add_arc((40, 20), 6, 30, 300)
        msp.add_arc((0, 0), 10, 300, 30)  # through 0 degrees
        msp.add_arc((5, 5), 3, 89.5, 90.5)

    def arc_mirrored(doc, msp):
        a = msp.add_arc((90, 60), 5, 10, 200)
        a.dxf.extrusion = (0, 0, -1)
        c = msp.add_circle((30, -10), 4)
        c.dxf.extrusion = (0, 0, -1)

    def ellipse(doc, msp):
        msp.add_ellipse((60, 20), major_axis=(8, 3), ratio=0.5, start_param=0.3, end_param=4.0)
        msp.add_ellipse((80, 20), major_axis=(-2, 7), ratio=0.3)
        msp.add_ellipse((0, 0), major_axis=(5, 0), ratio=0.6, start_param=5.0, end_param=1.0)
        e = msp.add_ellipse((20, -20), major_axis=(6, 2), ratio=0.4, start_param=0.5,
                            end_param=3.0)
        e.dxf.extrusion = (0, 0, -1)

    def lwpolyline(doc, msp):
        msp.add_lwpolyline([(0, 40, 0, 0, 0.5), (10, 40, 0, 0, -1), (20, 45, 0, 0, 0),
                            (25, 50, 0, 0, 2.5)], format='xyseb', close=True)
        msp.add_lwpolyline([(0, 0, 0.2), (5, 0, 0), (5, 5, -0.3), (0, 5, 0)], format='xyb')
        m = msp.add_lwpolyline([(0, 0, 0.4), (6, 1, 0), (6, 6, 0)], format='xyb')
        m.dxf.extrusion = (0, 0, -1)

    def polyline(doc, msp):
        msp.add_polyline2d([(30, 40, 0, 0, 0.3), (40, 40, 0, 0, 0), (40, 50, 0, 0, -0.7),
                            (33, 52)], format='xyseb', close=True)
        msp.add_polyline3d([(0, 0, 0), (10, 0, 5), (10, 10, -3)])

    def spline(doc, msp):
        msp.add_open_spline([(50, 40), (55, 50), (60, 40), (65, 50), (70, 40)], degree=3)
        msp.add_rational_spline([(0, 60), (10, 70), (20, 60), (30, 70)], [1, 2, 0.5, 1],
                                degree=2)
        msp.add_open_spline([(0, 0), (3, 8), (9, 2)], degree=2)
        msp.add_open_spline([(0, 0), (3, 4), (9, 2), (12, 7)], degree=1)

    def insert(doc, msp):
        b = doc.blocks.new('B1', base_point=(1, 1))
        b.add_line((1, 1), (5, 1))
        b.add_circle((3, 3), 2)
        b.add_arc((0, 0), 3, 0, 120)
        msp.add_blockref('B1', (100, 0), dxfattribs={'xscale': 2, 'yscale': 1.5,
                                                      'rotation': 30})
        msp.add_blockref('B1', (0, 50), dxfattribs={'xscale': -1, 'rotation': 45})
        n = doc.blocks.new('N1')
        n.add_blockref('B1', (10, 10), dxfattribs={'rotation': 90, 'xscale': 0.5,
                                                   'yscale': 0.5})
        n.add_lwpolyline([(0, 0, 1), (4, 0, 0)], format='xyb')
        msp.add_blockref('N1', (-30, -30), dxfattribs={'rotation': -20, 'xscale': 3,
                                                       'yscale': 3})
        r = msp.add_blockref('B1', (40, -40))
        r.dxf.extrusion = (0, 0, -1)

    def solid(doc, msp):  # drawn as outlines (warned: fills are not drawn)
        msp.add_solid([(0, 0), (4, 0), (0, 3), (4, 3)])
        msp.add_solid([(10, 0), (14, 1), (11, 4)])
        t = msp.add_trace([(20, 0), (24, 0), (20, 2), (24, 2)])
        t.dxf.extrusion = (0, 0, -1)
        msp.add_3dface([(30, 0, 0), (35, 0, 1), (35, 5, 2), (30, 5, 0)])

    return [(f.__name__, f) for f in (line, circle, arc, arc_mirrored, ellipse, lwpolyline,
                                       polyline, spline, insert, solid)]


def write(outdir):
    import ezdxf
    from ezdxf import disassemble, path
    for name, fn in cases():
        doc = ezdxf.new('R2010')
        doc.header['$INSUNITS'] = 4  # mm
        msp = doc.modelspace()
        fn(doc, msp)
        doc.saveas('%s/%s.dxf' % (outdir, name))
        with open('%s/%s.ref' % (outdir, name), 'w') as f:
            for e in disassemble.recursive_decompose(msp):
                if e.dxftype() == 'INSERT':
                    continue
                if e.dxftype() == 'SPLINE':  # the exact NURBS (make_path approximates it)
                    pts = list(e.construction_tool().flattening(0.0002, segments=16))
                else:  # make_path: arcs as cubic Beziers, within 2.7e-4 of the radius
                    pts = list(path.make_path(e).flattening(0.0002))
                for p in pts:
                    f.write('%.9f %.9f\n' % (p.x, p.y))
                f.write('\n')


def read_polys(fname):
    polys, cur = [], []
    for ln in open(fname):
        ln = ln.split()
        if not ln:
            if cur:
                polys.append(cur)
            cur = []
            continue
        cur.append((float(ln[0]), float(ln[1])))
    if cur:
        polys.append(cur)
    return polys


def seg_dist(p, a, b):
    dx, dy = b[0] - a[0], b[1] - a[1]
    l2 = dx * dx + dy * dy
    t = 0.0 if l2 == 0 else max(0.0, min(1.0, ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2))
    return math.hypot(p[0] - a[0] - t * dx, p[1] - a[1] - t * dy)


def farthest(pts, polys, cell=1.0):
    """Largest distance from a point of pts to the segments of polys (grid-bucketed)."""
    grid = {}
    for pl in polys:
        segs = list(zip(pl, pl[1:])) if len(pl) > 1 else [(pl[0], pl[0])]
        for a, b in segs:
            for i in range(int(math.floor(min(a[0], b[0]) / cell)) - 1,
                           int(math.floor(max(a[0], b[0]) / cell)) + 2):
                for j in range(int(math.floor(min(a[1], b[1]) / cell)) - 1,
                               int(math.floor(max(a[1], b[1]) / cell)) + 2):
                    grid.setdefault((i, j), []).append((a, b))
    worst = 0.0
    for p in pts:
        i, j = int(math.floor(p[0] / cell)), int(math.floor(p[1] / cell))
        near = grid.get((i, j), [])
        d = min((seg_dist(p, a, b) for a, b in near), default=float('inf'))
        worst = max(worst, d)
    return worst


def compare(ref, out, tol):
    a, b = read_polys(ref), read_polys(out)
    pa = [p for pl in a for p in pl]
    pb = [p for pl in b for p in pl]
    if not pa or not pb:
        print('empty: %d reference points, %d output points' % (len(pa), len(pb)))
        return 1
    ab, ba = farthest(pa, b), farthest(pb, a)
    print('max ref->out %.6f mm, out->ref %.6f mm (%d / %d points)' % (ab, ba, len(pa), len(pb)))
    return 0 if ab <= tol and ba <= tol else 1


if __name__ == '__main__':
    if sys.argv[1] == 'write':
        write(sys.argv[2])
    else:
        sys.exit(compare(sys.argv[2], sys.argv[3], float(sys.argv[4])))
