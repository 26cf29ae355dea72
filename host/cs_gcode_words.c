/* cs_gcode_words: modal groups and names of the G and M codes (see cs_gcode_words.h; LinuxCNC's
 * G-code reference, "Modal Groups"). */
#include "cs_gcode_words.h"

#include <stdio.h>

cs_gcode_group_t cs_gcode_group_g(int g)
{
    switch (g) {
    case GC_G4:
    case GC_G10:
    case GC_G28:
    case GC_G28_1:
    case GC_G30:
    case GC_G30_1:
    case GC_G52:
    case GC_G53:
    case GC_G92:
    case GC_G92_1:
    case GC_G92_2:
    case GC_G92_3:
        return GC_GROUP_NONMODAL;
    case GC_G17:
    case GC_G18:
    case GC_G19:
        return GC_GROUP_PLANE;
    case GC_G90:
    case GC_G91:
        return GC_GROUP_DISTANCE;
    case GC_G90_1:
    case GC_G91_1:
        return GC_GROUP_ARC_DIST;
    case GC_G93:
    case GC_G94:
        return GC_GROUP_FEED_MODE;
    case GC_G20:
    case GC_G21:
        return GC_GROUP_UNITS;
    case GC_G40:
        return GC_GROUP_CUTTER;
    case GC_G49:
        return GC_GROUP_TOOL_LEN;
    case GC_G61:
    case GC_G61_1:
    case GC_G64:
        return GC_GROUP_PATH;
    case GC_G98:
    case GC_G99:
        return GC_GROUP_RETURN;
    default:
        break;
    }
    if (cs_gcode_coord_system(g) != 0)
        return GC_GROUP_COORD;
    if (g == GC_G0 || g == GC_G1 || g == GC_G2 || g == GC_G3 || g == GC_G5 || g == GC_G5_1 ||
        g == GC_G5_2 || g == GC_G5_3 || g == GC_G6_2 || g == GC_G33 || g == GC_G33_1 ||
        (g >= GC_G38_2 && g <= GC_G38_5) || g == GC_G73 || g == GC_G74 || g == GC_G76 ||
        (g >= GC_G80 && g <= GC_G89 && g % 10 == 0))
        return GC_GROUP_MOTION;
    return GC_GROUP_NONE;
}

cs_gcode_group_t cs_gcode_group_m(int m)
{
    switch (m) {
    case GC_M2:
    case GC_M30:
        return GC_GROUP_M_STOP;
    case GC_M3:
    case GC_M4:
    case GC_M5:
        return GC_GROUP_M_SPINDLE;
    case GC_M7:
    case GC_M8:
    case GC_M9:
        return GC_GROUP_M_COOLANT;
    default:
        return GC_GROUP_NONE;
    }
}

int cs_gcode_coord_system(int g)
{
    /* G54 G55 G56 G57 G58 G59 G59.1 G59.2 G59.3: systems 1 .. 9 (LinuxCNC "G54-G59.3"). */
    static const int codes[] = {GC_G54, GC_G55,   GC_G56,   GC_G57,  GC_G58,
                                GC_G59, GC_G59_1, GC_G59_2, GC_G59_3};
    for (int k = 0; k < (int)(sizeof codes / sizeof codes[0]); k++)
        if (codes[k] == g)
            return k + 1;
    return 0;
}

void cs_gcode_code_name(char *out, unsigned cap, char letter, int code)
{
    if (code % 10)
        snprintf(out, cap, "%c%d.%d", letter, code / 10, code % 10);
    else
        snprintf(out, cap, "%c%d", letter, code / 10);
}
