/* cs_grbl_ov: the override percentages (see cs_grbl_ov.h). Bytes and steps from the grbl wiki,
 * "Interface", "Real-time commands": 0x90 feed 100 %, 0x91 / 0x92 +/-10 %, 0x93 / 0x94 +/-1 %;
 * 0x95 rapid 100 %, 0x96 50 %, 0x97 25 %; 0x99 spindle 100 %, 0x9A / 0x9B +/-10 %,
 * 0x9C / 0x9D +/-1 %. */
#include "cs_grbl_ov.h"

void cs_grbl_ov_init(cs_grbl_ov_t *ov)
{
    ov->feed = ov->rapid = ov->spindle = 100;
}

static int clamp_ov(int v)
{
    return v < CS_GRBL_OV_MIN ? CS_GRBL_OV_MIN : v > CS_GRBL_OV_MAX ? CS_GRBL_OV_MAX : v;
}

/* The steps of one percentage, from its "back to 100 %" byte first. */
static bool step(int *v, unsigned char b, unsigned char reset)
{
    static const int delta[] = {0, 10, -10, 1, -1};
    if (b < reset || b > reset + 4)
        return false;
    *v = b == reset ? 100 : clamp_ov(*v + delta[b - reset]);
    return true;
}

bool cs_grbl_ov_byte(cs_grbl_ov_t *ov, unsigned char b)
{
    if (step(&ov->feed, b, 0x90) || step(&ov->spindle, b, 0x99))
        return true;
    if (b == 0x95 || b == 0x96 || b == 0x97) {
        ov->rapid = b == 0x95 ? 100 : b == 0x96 ? 50 : 25;
        return true;
    }
    return b == 0x98; /* reserved in Grbl 1.1: taken, nothing changes */
}

void cs_grbl_ov_apply(const cs_grbl_ov_t *ov, cs_path_t *path, size_t n0, double default_mm_s,
                      double rapid_mm_s)
{
    for (size_t k = n0; k < path->n; k++) {
        cs_path_elem_t *el = &path->elems[k];
        if (el->rapid && ov->rapid < 100) {
            el->rapid = false;
            el->feed_mm_s = rapid_mm_s * ov->rapid / 100.0;
        } else if (!el->rapid && ov->feed != 100) {
            el->feed_mm_s = (el->feed_mm_s > 0 ? el->feed_mm_s : default_mm_s) * ov->feed / 100.0;
        }
    }
}
