# Test surfaces shared by tests/cli/test_dropcut_shapes.sh and tests/bench/dropcut_matrix.sh
# (sourced, never run). Each writes a curvestep-surfaces file computed here, independently of the
# code under test, inside the 3018 router's travel.

# cs_shape_cup FILE: a teacup, a surface of revolution from its profile (r, z above the foot at
# z = -20, axis at (15, 15)): an outer wall, a rounded rim, an inner wall into a flat bottom.
# Each profile cubic is turned by four quarter arcs with handles k = 4/3 tan(pi/8); patch row i =
# profile point i, column j = arc point j (the exact tensor product of the profile and the arc).
cs_shape_cup() {
    awk 'BEGIN {
    pi = 3.14159265358979; k = 4 / 3 * sin(pi / 8) / cos(pi / 8); n = 0
    seg[n++] = "4 0  5.5 1  6 3  6 5"            # outer wall
    seg[n++] = "6 5  6 5.6  5.2 5.6  5.2 5"      # rounded rim
    seg[n++] = "5.2 5  5.2 3  4.5 1.5  3 1"      # inner wall into the bottom
    seg[n++] = "3 1  2 1  1 1  0 1"              # inner bottom, flat, to the axis
    print "curvestep-surfaces 1"
    for (s = 0; s < n; s++) {
        split(seg[s], q, " ")
        for (a = 0; a < 4; a++) {
            t = a * pi / 2; c = cos(t); d = sin(t)
            ax[0] = c; ay[0] = d; ax[1] = c - k * d; ay[1] = d + k * c
            ax[3] = -d; ay[3] = c; ax[2] = -d + k * c; ay[2] = c + k * d
            print "bezier 3 3"
            for (i = 0; i < 4; i++) {
                line = " "
                for (j = 0; j < 4; j++)
                    line = line sprintf(" %.9g %.9g %.9g", 15 + q[2 * i + 1] * ax[j],
                                        15 + q[2 * i + 1] * ay[j], -20 + q[2 * i + 2])
                print line
            }
        }
    }
}' >"$1"
}

# cs_shape_pent FILE: the five-sided patch of tests/data/surfaces/pentagon.txt, halved and moved
# into the router's travel (x' = x / 2 + 15, y' = y / 2 + 15, z' = z / 2 - 20).
cs_shape_pent() {
    awk 'NF > 3 && $1 == 3 { l = "  3"; for (i = 2; i <= NF; i += 3)
        l = l sprintf("  %.6g %.6g %.6g", $i / 2 + 15, $(i + 1) / 2 + 15, $(i + 2) / 2 - 20)
    print l; next } { print }' tests/data/surfaces/pentagon.txt >"$1"
}
