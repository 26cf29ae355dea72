( Made using CamBam - http://www.cambam.co.uk )
( curvestep test data in the style of CamBam's router output )
( T0 : 3.175 )
G21 G90 G91.1 G64 G40
G0 Z3.0
( T0 : 3.175 )
T0 M6
( Profile1 )
G17
M3 S1000
G0 X10.0 Y10.0
G0 Z1.0
G1 F300.0 Z-1.0
G1 F600.0 X30.0
G3 X40.0 Y20.0 I0.0 J10.0
G1 Y30.0
G0 Z3.0
M5
M30
