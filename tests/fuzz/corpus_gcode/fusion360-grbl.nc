%
(1001)
(Machine)
(  vendor: Autodesk)
(  description: Generic Grbl)
(T1  D=3.175 CR=0 - ZMIN=-1 - flat end mill)
G90 G94
G17
G21

(2D Contour1)
T1
S10000 M3
G54
(the first positioning has no G0: Grbl is in G0 after reset)
X5 Y5
Z5
G1 Z-1 F300
G1 X25 F600
Y15
G3 X15 Y25 I-10 J0
G1 X5
Y5
G0 Z5
M5
M30
%
