(avr_job.nc: a small job for the ATmega328p test, tests/fw/test_fw_avr.sh: written for this)
(project; every axis changes direction, lines, arcs both ways, rapid and feed moves, about 2 s.)
G21 G90 G17
G0 X2 Y-1 Z1
G1 Z-0.5 F600
G1 X12 Y-1 F3000
G2 X12 Y9 I0 J5
G1 X4 Y9
G3 X2 Y7 I0 J-2
G1 X2 Y-1 Z0.25
G1 X7 Y4 Z-0.25 F1800
G0 Z1
