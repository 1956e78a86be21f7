; A five-pointed star outline (outer radius 10 mm, inner 4 mm) about the work origin,
; drawn with incremental moves (G91) after an absolute rapid to the top point.
G21 G90
G0 X0.000 Y10.000
G91 F1500
G1 X-2.351 Y-6.764
G1 X-7.160 Y-0.146
G1 X5.707 Y-4.326
G1 X-2.074 Y-6.854
G1 X5.878 Y4.090
G1 X5.878 Y-4.090
G1 X-2.074 Y6.854
G1 X5.707 Y4.326
G1 X-7.160 Y0.146
G1 X-2.351 Y6.764
G90 G0 X0 Y0
M400
