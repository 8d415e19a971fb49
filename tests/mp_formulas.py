"""The paper's total-phase formula in mpmath, shared by the accuracy tests.

eqn:GeometricPhase (with eqn:TK) written literally, at whatever precision
the caller sets with ``mp.workdps``: the independent reference for the
compiled closed form, which uses Bulirsch's ``cel`` instead of K and Pi.
"""

import mpmath as mp


def elliptic_parameters(i1, i2, i3, two_e, m_sq, sam=None):
    """``k^2``, the rate, Pi's characteristic ``n`` and the shift (2 pi on SAM).

    ``sam`` picks the branch; by default ``M^2 > 2 E I2``.  Give it where the
    spin is so close to the separatrix that the precision cannot decide.
    """
    if sam is None:
        sam = m_sq > two_e * i2
    if sam:
        k2 = (i2 - i1) * (two_e * i3 - m_sq) / ((i3 - i2) * (m_sq - two_e * i1))
        rate = mp.sqrt((i3 - i2) * (m_sq - two_e * i1) / (i1 * i2 * i3))
        return k2, rate, -i3 * (i2 - i1) / (i1 * (i3 - i2)), 2 * mp.pi
    k2 = (i3 - i2) * (m_sq - two_e * i1) / ((i2 - i1) * (two_e * i3 - m_sq))
    rate = mp.sqrt((i2 - i1) * (two_e * i3 - m_sq) / (i1 * i2 * i3))
    return k2, rate, -i3 * (m_sq - two_e * i1) / (i1 * (two_e * i3 - m_sq)), 0


def period_and_total_phase(i1, i2, i3, two_e, m_sq, sam=None):
    """``T`` (eqn:TK) and ``Delta alpha`` (eqn:GeometricPhase), mpmath numbers."""
    k2, rate, n, shift = elliptic_parameters(i1, i2, i3, two_e, m_sq, sam)
    momentum = mp.sqrt(m_sq)
    period = 4 * mp.ellipk(k2) / rate
    total = (
        momentum * period / i3
        + 4 * momentum * (i3 - i1) * mp.ellippi(n, k2) / (i1 * i3 * rate)
        - shift
    )
    return period, total
