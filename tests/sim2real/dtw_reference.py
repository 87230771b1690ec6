#!/usr/bin/env python3
"""Reference DTW distances from the Python package similaritymeasures (the paper's tool, §3.1).

Usage: dtw_reference.py DIR COUNT
Reads DIR/a_<k>.txt and DIR/b_<k>.txt (whitespace-separated, one point per row) for
k = 0..COUNT-1 and prints similaritymeasures.dtw(a, b)[0] for each k, one per line, with
17 significant digits. Called by tests/sim2real/dtw_reference_test.cpp.
"""
import sys

import numpy as np
import similaritymeasures


def main() -> int:
    folder, count = sys.argv[1], int(sys.argv[2])
    for k in range(count):
        a = np.loadtxt(f"{folder}/a_{k}.txt", ndmin=2)
        b = np.loadtxt(f"{folder}/b_{k}.txt", ndmin=2)
        distance, _ = similaritymeasures.dtw(a, b)
        print(f"{distance:.17g}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
