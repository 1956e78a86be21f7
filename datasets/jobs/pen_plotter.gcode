; nnik-machine: tool=pen
; issue 20's pen-plotter job: the pen goes up with G0 Z5 and down with G1 Z0 (D11 high = down)
G21 G90
G0 Z5
G0 X-6 Y-6
G1 Z0 F1000
G1 X6 Y-6 F2400
G1 X6 Y6
G1 X-6 Y6
G1 X-6 Y-6
G0 Z5
G0 X0 Y-4
G1 Z0 F1000
G2 X0 Y-4 I0 J4 F2400
G0 Z5
G0 X0 Y0
