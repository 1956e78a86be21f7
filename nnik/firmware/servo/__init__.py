"""The closed-loop XY table's firmware (issue 28): the servo runtime (codegen/arduino/src/
nnik_servo.c) with a controller built for the simulated Uno (build), run in lockstep with the
Python plant (cosim), exported as an Arduino library (export), measured (nnik.bench.servo)."""
