"""orbits.core.exact: error-free products and sums for the separatrix gap."""

import math

import numpy as np

# ------------------------------------------------------------------------
# Each test below kills a mutant of orbits/core/exact.py that passed the suite (a
# mutation audit of the core kernels, 2026-11-29: 49 mutants, 11 survivors
# that changed an output).


def test_separatrix_gap_is_exact_to_1e_30_of_its_terms():
    """E1/E2/E3: separatrix_gap_exact against the exact rational value (Fraction
    arithmetic on the given doubles) for spins within rounding of the
    separatrix.  Original: |err| <= 6.8e-32 of the term I3 (I3-I2) w3^2;
    mutants (splitter 2**26+1, d21's low part dropped, low parts dropped):
    1e-16..4e-16."""
    from fractions import Fraction as F

    from orbits.core.exact import separatrix_gap_exact

    rng = np.random.default_rng(5)
    worst = 0.0
    for _ in range(400):
        i1 = rng.uniform(0.01, 0.3)
        i2 = rng.uniform(0.6, 0.9)
        i3 = rng.uniform(i2 + 0.01, min(i1 + i2, 1.5))
        w1 = rng.uniform(0.2, 1.0)
        w3 = float(math.sqrt(i1 * (i2 - i1) / (i3 * (i3 - i2))) * w1)
        term = F(i3) * (F(i3) - F(i2)) * F(w3) ** 2
        exact = term - F(i1) * (F(i2) - F(i1)) * F(w1) ** 2
        got = separatrix_gap_exact(i1, i2, i3, w1, w3)
        worst = max(worst, float(abs(F(got) - exact) / term))
    assert worst <= 1e-30, worst
