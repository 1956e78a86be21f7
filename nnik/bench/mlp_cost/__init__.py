"""The MLP cost model's measurements (nnik.implementations.mlp.cost predicts): the calibration
runs on the simulators, the validation sweep over trained networks and the search-space check.

    python3 -m nnik.bench.mlp_cost calibrate --target avr|pic18 [--profile P] [--kernel fast]
    python3 -m nnik.bench.mlp_cost sweep [--record]
    python3 -m nnik.bench.mlp_cost search-check [--record]
"""
