/* cs_gcode_words: the G and M codes and modal groups of the G-code reader, by name (as Grbl's
 * gcode.h names them), so that the interpreter (cs_gcode*.c) and the Grbl front end never spell
 * a code as a bare number. A code is kept in tenths: G38.2 is GC_G38_2 == 382, M30 is GC_M30 ==
 * 300. The groups are the modal groups of LinuxCNC's G-code reference, "Modal Groups" (table
 * "G-code Modal Groups" and "M-code Modal Groups"). Host only. */
#ifndef CS_GCODE_WORDS_H
#define CS_GCODE_WORDS_H

#include <stdbool.h>

/* G codes (tenths). */
enum {
    GC_G0 = 0,
    GC_G1 = 10,
    GC_G2 = 20,
    GC_G3 = 30,
    GC_G4 = 40,
    GC_G5 = 50,
    GC_G5_1 = 51,
    GC_G5_2 = 52,
    GC_G5_3 = 53,
    GC_G6_2 = 62,
    GC_G10 = 100,
    GC_G17 = 170,
    GC_G18 = 180,
    GC_G19 = 190,
    GC_G20 = 200,
    GC_G21 = 210,
    GC_G28 = 280,
    GC_G28_1 = 281,
    GC_G30 = 300,
    GC_G30_1 = 301,
    GC_G33 = 330,
    GC_G33_1 = 331,
    GC_G38_2 = 382,
    GC_G38_3 = 383,
    GC_G38_4 = 384,
    GC_G38_5 = 385,
    GC_G40 = 400,
    GC_G49 = 490,
    GC_G52 = 520,
    GC_G53 = 530,
    GC_G54 = 540,
    GC_G55 = 550,
    GC_G56 = 560,
    GC_G57 = 570,
    GC_G58 = 580,
    GC_G59 = 590,
    GC_G59_1 = 591,
    GC_G59_2 = 592,
    GC_G59_3 = 593,
    GC_G61 = 610,
    GC_G61_1 = 611,
    GC_G64 = 640,
    GC_G73 = 730,
    GC_G74 = 740,
    GC_G76 = 760,
    GC_G80 = 800,
    GC_G81 = 810,
    GC_G83 = 830,
    GC_G89 = 890,
    GC_G90 = 900,
    GC_G90_1 = 901,
    GC_G91 = 910,
    GC_G91_1 = 911,
    GC_G92 = 920,
    GC_G92_1 = 921,
    GC_G92_2 = 922,
    GC_G92_3 = 923,
    GC_G93 = 930,
    GC_G94 = 940,
    GC_G98 = 980,
    GC_G99 = 990,
};

/* M codes (tenths). */
enum {
    GC_M2 = 20,
    GC_M3 = 30,
    GC_M4 = 40,
    GC_M5 = 50,
    GC_M7 = 70,
    GC_M8 = 80,
    GC_M9 = 90,
    GC_M30 = 300,
};

/* Modal groups (LinuxCNC's numbers in the comments). */
typedef enum {
    GC_GROUP_NONE = 0,   /* not a code this table knows */
    GC_GROUP_NONMODAL,   /* 0: G4 G10 G28 G28.1 G30 G30.1 G53 G92 G92.1 G92.2 G92.3 */
    GC_GROUP_MOTION,     /* 1: G0 G1 G2 G3 G5 G5.1 G5.2 G5.3 G6.2 G33 G38.n G73 G76 G80-G89 */
    GC_GROUP_PLANE,      /* 2: G17 G18 G19 */
    GC_GROUP_DISTANCE,   /* 3: G90 G91 */
    GC_GROUP_ARC_DIST,   /* 4: G90.1 G91.1 */
    GC_GROUP_FEED_MODE,  /* 5: G93 G94 */
    GC_GROUP_UNITS,      /* 6: G20 G21 */
    GC_GROUP_CUTTER,     /* 7: G40 */
    GC_GROUP_TOOL_LEN,   /* 8: G49 */
    GC_GROUP_COORD,      /* 12: G54-G59.3 */
    GC_GROUP_PATH,       /* 13: G61 G61.1 G64 */
    GC_GROUP_RETURN,     /* 10: G98 G99 (canned cycle return level) */
    GC_GROUP_M_STOP,     /* M 4: M2 M30 */
    GC_GROUP_M_SPINDLE,  /* M 7: M3 M4 M5 */
    GC_GROUP_M_COOLANT,  /* M 8: M7 M8 M9 */
} cs_gcode_group_t;

/* The modal group of G code g (tenths). */
cs_gcode_group_t cs_gcode_group_g(int g);
/* The modal group of M code m (tenths). */
cs_gcode_group_t cs_gcode_group_m(int m);
/* G54 .. G59.3 -> coordinate system 1 .. 9; 0 for any other code. */
int cs_gcode_coord_system(int g);
/* "G38.2", "M30": code (tenths) of letter into out[cap]. */
void cs_gcode_code_name(char *out, unsigned cap, char letter, int code);

#endif
