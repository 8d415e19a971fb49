"""Error-free transformations (double-double arithmetic) for one quantity.

A spin vector given in doubles defines an orbit exactly, but its distance
from the separatrix, ``M^2 - 2 E I2 = I3 (I3-I2) w3^2 - I1 (I2-I1) w1^2``,
cancels catastrophically in double precision near the separatrix.  Here it
is evaluated with Dekker's error-free products and Knuth's two-sum
(T. J. Dekker, Numer. Math. 18, 224 (1971); D. E. Knuth, TAOCP vol. 2,
4.2.2), to about 1e-32 relative to its terms, then rounded once.
"""

from numba import njit

_SPLITTER = 134217729.0  # 2**27 + 1


@njit(cache=True, nogil=True)
def two_sum(a, b):
    """``a + b = s + e`` exactly."""
    s = a + b
    bb = s - a
    return s, (a - (s - bb)) + (b - bb)


@njit(cache=True, nogil=True)
def _split(a):
    c = _SPLITTER * a
    hi = c - (c - a)
    return hi, a - hi


@njit(cache=True, nogil=True)
def two_product(a, b):
    """``a * b = p + e`` exactly (Dekker, no fused multiply-add needed)."""
    p = a * b
    ah, al = _split(a)
    bh, bl = _split(b)
    return p, ((ah * bh - p) + ah * bl + al * bh) + al * bl


@njit(cache=True, nogil=True)
def _dd_times(hi, lo, b):
    p, e = two_product(hi, b)
    e += lo * b
    return two_sum(p, e)


@njit(cache=True, nogil=True)
def _dd_product_of_three(a, b_hi, b_lo, c):
    """``a * (b_hi + b_lo) * c * c`` in double-double."""
    hi, lo = two_product(a, b_hi)
    lo += a * b_lo
    hi, lo = two_sum(hi, lo)
    hi, lo = _dd_times(hi, lo, c)
    return _dd_times(hi, lo, c)


@njit(cache=True, nogil=True)
def separatrix_gap_exact(i1, i2, i3, w1, w3):
    """``I3 (I3-I2) w3^2 - I1 (I2-I1) w1^2`` correctly rounded (to ~1e-32).

    ``M^2 - 2 E I2`` of the spin ``(w1, w2, w3)``; ``w2`` drops out.
    """
    d32_hi, d32_lo = two_sum(i3, -i2)
    d21_hi, d21_lo = two_sum(i2, -i1)
    a_hi, a_lo = _dd_product_of_three(i3, d32_hi, d32_lo, w3)
    b_hi, b_lo = _dd_product_of_three(i1, d21_hi, d21_lo, w1)
    s, e = two_sum(a_hi, -b_hi)
    return s + (e + (a_lo - b_lo))
