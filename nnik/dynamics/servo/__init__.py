"""DC-servo axes (issue 28, seed 001's XY table): the plant, the identified speed model, the
identification from a log, and the Python closed loop. One small module per concern."""
