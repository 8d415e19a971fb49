"""sin and cos by polynomials, for compiled loops that LLVM can vectorise.

``sin_small``/``cos_small`` are Taylor polynomials on ``|x| <= pi/4``;
:func:`sincos` reduces any moderate argument to that range by
Cody-Waite's three-part ``pi/2`` (W. J. Cody and W. Waite, *Software Manual
for the Elementary Functions*, 1980, ch. 8): each part has at most 33
significant bits, so ``k * part`` is exact for ``|k| < 2**20``.
"""

import math

from numba import njit

# Taylor coefficients (-1)^k / (2k+1)! and (-1)^k / (2k)!: on |x| <= pi/4 the
# first omitted terms are below 1e-19, so the polynomials are good to ~1 ulp
_S3, _S5, _S7, _S9 = (
    -0.16666666666666666,
    0.008333333333333333,
    -0.0001984126984126984,
    2.7557319223985893e-06,
)
_S11, _S13, _S15, _S17 = (
    -2.505210838544172e-08,
    1.6059043836821613e-10,
    -7.647163731819816e-13,
    2.8114572543455206e-15,
)
_C4, _C6, _C8, _C10 = (
    0.041666666666666664,
    -0.001388888888888889,
    2.48015873015873e-05,
    -2.755731922398589e-07,
)
_C12, _C14, _C16, _C18 = (
    2.08767569878681e-09,
    -1.1470745597729725e-11,
    4.779477332387385e-14,
    -1.5619206968586225e-16,
)


@njit(cache=True, nogil=True, inline="always")
def sin_small(x):
    """``sin x`` for ``|x| <= pi/4`` (Taylor, Horner in ``x^2``): SIMD-friendly."""
    z = x * x
    return x + x * z * (
        _S3 + z * (_S5 + z * (_S7 + z * (_S9 + z * (_S11 + z * (_S13 + z * (_S15 + z * _S17))))))
    )


@njit(cache=True, nogil=True, inline="always")
def cos_small(x):
    """``cos x`` for ``|x| <= pi/4`` (Taylor, Horner in ``x^2``)."""
    z = x * x
    return (
        1.0
        - 0.5 * z
        + z
        * z
        * (
            _C4
            + z * (_C6 + z * (_C8 + z * (_C10 + z * (_C12 + z * (_C14 + z * (_C16 + z * _C18))))))
        )
    )


# pi/2 = PIO2_1 + PIO2_2 + PIO2_3 (+ ~1e-37); PIO2_1 and PIO2_2 have 33
# significant bits (split from 76 digits of pi/2 with exact rationals)
PIO2_1 = 1.5707963267341256
PIO2_2 = 6.077100506303966e-11
PIO2_3 = 2.0222662487959506e-21
TWO_OVER_PI = 2.0 / math.pi
# below this |x| the reduction is exact to rounding (|k| < 2**19)
SINCOS_LIMIT = 8.0e5


@njit(cache=True, nogil=True)
def sincos(x):
    """``(sin x, cos x)`` to ~1 ulp; ``math.sin``/``math.cos`` for ``|x| > SINCOS_LIMIT``."""
    if not abs(x) <= SINCOS_LIMIT:
        return math.sin(x), math.cos(x)
    k = math.floor(x * TWO_OVER_PI + 0.5)
    r = ((x - k * PIO2_1) - k * PIO2_2) - k * PIO2_3
    s = sin_small(r)
    c = cos_small(r)
    quadrant = int(k) & 3
    if quadrant == 0:
        return s, c
    if quadrant == 1:
        return c, -s
    if quadrant == 2:
        return -s, -c
    return -c, s
