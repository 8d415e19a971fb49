"""Exact motion: angular velocity, Euler angles and orientation in time.

:class:`Motion` evaluates the closed-form solution of Euler's equations
(eqn:Omegas, eqn:eulerangles, eqn:fullphi; see :mod:`orbits.core.motion`)
on any time grid.  Conventions:

* body frame = principal axes sorted ``I1 < I2 < I3``;
* space frame: z along the (conserved) angular momentum M, and the Euler
  angle ``phi(0) = 0``;
* orientation ``R(t)`` maps body components to space components,
  ``R = Rz(phi) Rx(theta) Rz(psi)`` (z-x'-z'', Goldstein Fig. 4.7 / Landau
  Sec. 35);
* after one period ``R(T) = Rot(+z, Delta alpha) R(0)``: the herpolhode
  closes exactly when ``Delta alpha`` is a whole number of turns.

Units: the body's moments as given and omega as given (rad per unit time);
:func:`polhode` and :func:`herpolhode` use the paper's ``|I| = 1`` and
``|omega0| = 1``.

Accuracy of the start: ``omega(0)`` reproduces ``omega0`` to a few ulps in
every component, for every spin, down to ``dtheta = 1e-300`` and for
spins within 1e-300 of the unstable I2 axis (the start argument is kept
as a whole number of quarter periods plus an offset formed through
Carlson's ``R_F``, :func:`orbits.core.motion.start_offset`; the separatrix
gap of a spin whose small components have subnormal squares is formed
from them scaled by a power of two, and the ``R_J`` of ``phi(t)`` near the
saddle from ``cn`` and ``dn`` themselves,
:func:`orbits.core.elliptic.carlson_rj_roots`).

Accuracy of phi (tested against an mpmath quadrature of Landau's ``dphi/dt
= M (I1 w1^2 + I2 w2^2) / (I1^2 w1^2 + I2^2 w2^2)``): the total phase and
``phi(t)`` within a few ulps (measured 5e-16 relative; ``phi`` relative to
``max(1, |phi|)``) and ``R(t)`` within 5e-15 (1.4e-14 at ``dtheta =
1e-12``, on the orbit of the double omega0), for ordinary bodies and thin
rods ``(e, 1, 1 + e)`` down to ``e = 2^-52``.  The incomplete ``Pi(n; .)``
of eqn:fullphi has ``n ~ -1/e^2`` on a thin rod; it is taken from a
cancellation-free form (:func:`orbits.core.motion.pi_far`), and times are
reduced by whole periods first, so that ``phi(k T) = k phi(T)`` to
rounding, whatever the rounding of ``D T`` against ``4 K``.  (Before, the
total phase was off by 1e-10 at ``e = 1e-6``, 2e-7 at 1e-9, 4e-4 at 1e-12
and O(1) at 1e-15.)  One limit is the Euler angles' own: where the I3 axis
passes within ~``I1/I3`` of M (a thin rod spun with ``w2 = 0`` does so at
``t = 0, T/2, T, ...``), phi and psi each turn by ~pi within a time
~``I1/M``, so the rounding of ``u = D t`` (``eps K``) moves them by up to
~``eps K M / (I1 D)`` in opposite directions (measured 1e-2 at ``e =
1e-15``, 4e-11 at 1e-6); the orientation (``rotation``, ``quaternion``),
theta and ``phi + psi`` stay accurate there.
"""

import math
import warnings
from collections import namedtuple

import numpy as np

from ._args import integer, real_array, real_scalar
from .bodies import Body
from .core import grid as _grid_kernels
from .core import motion as _kernels
from .core import phase as _phase
from .errors import AngleError, InputError, SeparatrixError
from .phases import TOO_NEAR_SEPARATRIX, total_phase
from .threads import size_aware

MotionState = namedtuple("MotionState", ["t", "omega", "euler", "rotation", "omega_space"])
MotionState.__doc__ = """The motion on a time grid.

t : (n,) times; omega : (n, 3) body-frame angular velocity;
euler : (n, 3) Euler angles (phi, theta, psi), radians, phi and psi
unwrapped; rotation : (n, 3, 3) body -> space; omega_space : (n, 3) the
angular velocity in the space frame (z along M).
"""


class TumblingPeriods(
    namedtuple("TumblingPeriods", ["precession", "rotation", "ratio", "axis", "about_momentum"])
):
    """Periods of a tumbling body; see :meth:`Motion.tumbling_periods`.

    precession : P_phi; rotation : P_psi (= T); ratio : P_psi / P_phi;
    axis : "short" (SAM) or "long" (LAM), the axis whose Euler angles these are;
    about_momentum : 2 pi T / Delta alpha, the mean rotation period about L.
    Periods in the time unit of omega0 (s for rad/s).
    """

    __slots__ = ()

    def _repr_html_(self):
        from .units import html_table

        rows = [
            ("P_psi (rotation about the " + self.axis + " axis, = T)", self.rotation, "s"),
            ("P_phi (precession of that axis about L)", self.precession, "s"),
            ("P_psi / P_phi", self.ratio, ""),
            ("2 pi T / Delta alpha (mean rotation about L)", self.about_momentum, "s"),
        ]
        return html_table(
            "TumblingPeriods (Pravec et al. 2005; s when omega0 is in rad/s)",
            [(name, float(value), unit) for name, value, unit in rows],
        )


class AxesWarning(UserWarning):
    """:meth:`Motion.from_omega` without ``axes`` for a body whose principal
    axes are not the axes it was given in (omega taken as principal)."""


def as_body(body_or_moments):
    """A :class:`Body` as given, or one built from moments of a single body."""
    if isinstance(body_or_moments, Body):
        return body_or_moments
    moments = real_array("moments", body_or_moments)
    if moments.ndim == 2 and moments.shape[-1] == 3 and moments.shape[0] != 1:
        raise InputError("the motion is computed for one body at a time")
    return Body(moments.reshape(-1) if moments.shape == (1, 3) else moments)


def _does_not_fit(what):
    return InputError(
        f"the {what} of this motion does not fit a double at this "
        "scale of the moments and omega0; rescale them"
    )


def _scaled(value, power, what):
    """``value * 2**power`` (exact), refused if it over- or underflows."""
    if np.ndim(value) == 0:
        value = float(value)
        try:
            out = math.ldexp(value, power)
        except OverflowError:
            out = math.inf
        if math.isfinite(out) and math.ldexp(out, -power) == value:
            return out
        raise _does_not_fit(what)
    if power == 0:  # the common |omega0| ~ 1: only the check (np.ldexp is slow)
        if np.isfinite(value).all():
            return value
        raise _does_not_fit(what)
    with np.errstate(over="ignore", under="ignore"):
        out = np.ldexp(value, power)
        back = np.ldexp(out, -power)
    if not np.all(np.isfinite(out)) or not np.array_equal(back, value):
        raise _does_not_fit(what)
    return out


# the largest |t| the motion takes, in periods (see ``Motion._times``)
TIME_LIMIT_PERIODS = 2.0**50


class Motion:
    """The torque-free motion of one body from one initial spin.

    Build with :meth:`from_spin` (polar angles, as elsewhere in ``orbits``)
    or :meth:`from_omega` (any vector, in the principal axes or in the
    body's own axes: its ``axes`` keyword).  Every vector the motion
    returns is in the principal frame (body side) or the space frame; a
    body-frame vector ``v`` is ``body.frame.T @ v`` in the axes the body
    was given in.

    Attributes
    ----------
    body : Body
    omega0 : ndarray, shape (3,)
        Initial angular velocity in the principal frame (``body.frame.T @
        omega0`` in the axes the body was given in).
    branch : str
        ``"SAM"`` or ``"LAM"``.
    energy, momentum : float
        E and M for the body's moments and omega0 as given (kg m^2 and
        rad/s give J and J s; the same convention as
        :func:`orbits.spin_phases`).
    D : float
        ``M^2 / (2E)`` (eqn:E, eqn:J), in the units of the moments, with
        ``I1 <= D <= I3``: the label of the orbit independent of
        ``|omega0|``.  ``D / |I|`` is the ``D`` column of a catalog row
        (which is for ``|I| = 1``).
    period : float
        T of eqn:TK, in the time unit of omega0.
    m : float
        Elliptic parameter k^2 (indices 1 <-> 3 on LAM).
    one_minus_m : float
        ``1 - k^2``, from the factored separatrix gap (accurate where ``m``
        rounds to 1, down to the smallest normal double, 2.2e-308; below
        that a subnormal with fewer digits, or 0 at ``|dtheta| ~ 1e-323``.
        The motion itself works with ``k_c = sqrt(1 - k^2)``, never below
        4.9e-312).
    """

    def __init__(self, body, omega0, _gap=None):
        body = as_body(body)
        omega0 = real_array("omega0", omega0, AngleError)
        if omega0.shape != (3,) or not all(math.isfinite(v) for v in omega0.tolist()):
            raise AngleError("omega0 must be a finite 3-vector")
        largest = max(abs(v) for v in omega0.tolist())
        if largest == 0.0:
            raise AngleError("omega0 must be nonzero")
        # Exact power-of-two scalings: the kernels see the unit moments of
        # the body and omega0 / 2**speed, with max |component| in [1/2, 1);
        # Euler's equations are homogeneous, so omega(t) = 2**speed u(2**speed t)
        # and E, M, T follow by exact rescaling (no overflow at any scale).
        speed = math.frexp(largest)[1]
        unit_omega = np.ldexp(omega0, -speed)
        i1, i2, i3 = body.unit_moments
        if _gap is None:
            # M^2 - 2 E I2 of unit_omega exactly, in factors free of underflow
            # near the I2 axis, from omega0 itself (unit_omega rounds a
            # subnormal component, and the gap of a nearly symmetric body
            # can hang on one)
            _gap = _phase.scaled_vector_gap(i1, i2, i3, float(omega0[0]), float(omega0[2]), speed)
        orbit = np.zeros(_kernels.ORBIT_SIZE)
        branch = _kernels.orbit_setup(i1, i2, i3, *unit_omega, *_gap, orbit)
        if branch == _phase.BRANCH_SEPARATRIX:
            raise SeparatrixError(
                "omega0 lies on the separatrix M^2 = 2 E I2 (infinite period), "
                + TOO_NEAR_SEPARATRIX
            )
        self.body = body
        self.omega0 = omega0.copy()  # not the caller's array (an edit there changed it)
        self.omega0.setflags(write=False)  # nor an edit of this one (repr, not the motion)
        self._orbit = orbit
        self._speed = speed
        self.branch = "SAM" if branch == _phase.BRANCH_SAM else "LAM"
        self.energy = float(
            _scaled(0.5 * orbit[_kernels.SLOT_TWO_E], body.exponent + 2 * speed, "energy")
        )
        self.momentum = float(
            _scaled(orbit[_kernels.SLOT_MOMENTUM], body.exponent + speed, "angular momentum")
        )
        self.period = float(_scaled(orbit[_kernels.SLOT_PERIOD], -speed, "period"))
        # D = M^2/(2E) depends on the moments only (units of the moments)
        self.D = float(
            _scaled(
                orbit[_kernels.SLOT_MOMENTUM] ** 2 / orbit[_kernels.SLOT_TWO_E], body.exponent, "D"
            )
        )
        self.m = orbit[_kernels.SLOT_M]
        self.one_minus_m = orbit[_kernels.SLOT_KC] ** 2

    @classmethod
    def from_omega(cls, body, omega, *, axes=None):
        """Motion from an initial angular velocity vector.

        Parameters
        ----------
        body : Body or array_like, shape (3,)
        omega : array_like, shape (3,)
            The initial angular velocity, any magnitude (rad per unit time).
        axes : {"principal", "body"}, optional
            The axes ``omega`` is given in:

            * ``"principal"``: along the sorted principal axes ``(I1, I2,
              I3)``, the frame of :attr:`omega0` and of every output;
            * ``"body"``: along the axes the body was given in (the order of
              the moments passed to :class:`Body`, the x y z of
              :meth:`Body.box`, the coordinates of a tensor, mesh or point
              masses), turned to the principal frame with :attr:`Body.frame`
              (``omega0 = body.frame @ omega``), as the command line's
              ``--omega`` is.

            May be left out only where the two coincide (``body.frame`` is
            the identity, e.g. moments given in ascending order); for any
            other body leaving it out takes ``"principal"`` (the meaning
            before the keyword existed) and warns with
            :class:`AxesWarning`, because a spin meant in the body's own
            axes would silently give another motion.

        Raises
        ------
        AngleError
            omega not a finite nonzero 3-vector.
        SeparatrixError
            omega on the separatrix (including a spin exactly along I2).
        InputError
            ``axes`` not one of the two names, or the energy, angular
            momentum or period of the motion does not fit a double at this
            scale of the moments and ``omega`` (rescale them).

        Warns
        -----
        AxesWarning
            ``axes`` left out for a body whose principal axes are not the
            axes it was given in.

        Examples
        --------
        A phone (edges along x y z) thrown at 120 rpm about its width x::

            phone = Body.box(0.071, 0.147, 0.0078, mass=0.17)
            spin = np.array([120.0, 2.0, 1.0]) * 2 * np.pi / 60
            motion = Motion.from_omega(phone, spin, axes="body")
            # the same motion: Motion.from_omega(phone, phone.frame @ spin, axes="principal")
        """
        body = as_body(body)
        if axes is not None and (not isinstance(axes, str) or axes not in ("principal", "body")):
            raise InputError(f"axes must be 'principal' or 'body', got {axes!r}")
        if axes == "body":
            omega = real_array("omega0", omega, AngleError)
            if omega.shape != (3,):
                raise AngleError("omega0 must be a finite 3-vector")
            omega = body.frame @ omega
        elif axes is None and not np.array_equal(body.frame, np.eye(3)):
            warnings.warn(
                "Motion.from_omega: omega taken along the principal axes (I1, I2, I3); "
                "this body was given in other axes (body.frame is not the identity). "
                "Pass axes='principal' to say so, or axes='body' for a spin along "
                "the body's own axes (as the command line's --omega)",
                AxesWarning,
                stacklevel=2,
            )
        return cls(body, omega)

    @classmethod
    def from_spin(cls, body, theta=None, *, dtheta=None, phi=0.0, speed=1.0):
        """Motion from ``omega0 = speed (sin t cos p, sin t sin p, cos t)``.

        ``theta`` (or the offset ``dtheta = theta - theta_crit``) and ``phi``
        as in :func:`orbits.total_phase`; with ``dtheta`` the separatrix
        distance keeps full precision (tested down to ``1 - m = 1e-12``).
        Any ``theta`` and ``phi`` are accepted: the motion is that of the
        spin as given, and its period, E, M and total phase equal those of
        the spin folded by :func:`orbits.phases.fold_angle`.

        Parameters
        ----------
        body : Body or array_like, shape (3,)
        theta : float, optional
            Polar angle of omega0 from the I3 axis, radians.
        dtheta : float, optional
            ``theta - theta_crit`` instead of ``theta`` (exactly one of the two).
        phi : float
            Azimuth of omega0 from the I1 axis, radians (default 0).
        speed : float
            ``|omega0|``, positive, rad per unit of the motion's time
            (default 1: times in units of ``1/|omega0|``).

        Raises
        ------
        AngleError, SeparatrixError
            As :func:`orbits.total_phase`; ``speed`` must be positive.
        """
        body = as_body(body)
        speed = real_scalar("speed", speed, AngleError)
        if not (math.isfinite(speed) and speed > 0.0):
            raise AngleError(f"speed must be positive, got {speed}")
        if (theta is None) == (dtheta is None):
            raise AngleError("give exactly one of theta and dtheta")
        phi = real_scalar("phi", phi, AngleError)
        if not math.isfinite(phi):
            raise AngleError(f"phi must be finite, got {phi}")
        from_offset = dtheta is not None
        angle = real_scalar(
            "dtheta" if from_offset else "theta", dtheta if from_offset else theta, AngleError
        )
        if not from_offset and math.isfinite(angle) and not 0.0 <= angle <= 0.5 * np.pi:
            # refused as total_phase refuses it: folded within rounding of
            # theta_c, or within the fold's rounding of the separatrix (a
            # spin there was computed 0.45 % off instead)
            total_phase(body, angle, phi=phi)
            # the spin as given (not folded: the motion differs by signs; its
            # T, E, M and total phase are those of the folded spin)
            return cls(
                body,
                speed
                * np.array(
                    [np.sin(angle) * np.cos(phi), np.sin(angle) * np.sin(phi), np.cos(angle)]
                ),
            )
        status, theta_, _, _, w1, w2, w3, scale, offset, closing = _phase.spin_from_angle(
            _phase.body_constants(*body.unit_moments, phi), angle, from_offset
        )
        if status == _phase.STATUS_NOT_FINITE:
            raise AngleError(f"{'dtheta' if from_offset else 'theta'} must be finite")
        if status == _phase.STATUS_OUT_OF_RANGE:
            if from_offset:
                # refused as total_phase refuses it (theta_c + dtheta, not folded)
                total_phase(body, dtheta=angle, phi=phi)
            raise AngleError(f"theta = {theta_!r} is outside [0, pi/2]")
        if status == _phase.STATUS_SEPARATRIX:
            raise SeparatrixError(
                "the spin lies on the separatrix, or theta is within the rounding "
                "error of theta_c (too near to tell SAM from LAM); pass a nonzero dtheta"
            )
        omega = [speed * w1, speed * w2, speed * w3]
        if not all(math.isfinite(v) for v in omega):
            raise AngleError(f"speed {speed!r} is too large for a double omega0")
        # the kernel sees omega / 2**k (see __init__); the gap scales like
        # omega's squares
        unit_speed = math.ldexp(speed, -math.frexp(max(abs(v) for v in omega))[1])
        return cls(body, np.array(omega), (scale * unit_speed * unit_speed, offset, closing))

    # ------------------------------------------------------------------
    def _times(self, t):
        """Times as an array (shape kept: a scalar stays shape ()) and in kernel units."""
        times = real_array("t", t)
        if not np.all(np.isfinite(times)):
            raise InputError("times must be finite")
        if self._speed == 0:
            scaled = times
        else:
            with np.errstate(over="ignore", under="ignore"):
                scaled = np.ldexp(times, self._speed)
        if self._speed > 0 and not np.all(np.isfinite(scaled)):
            raise InputError("times too large for this |omega0| (t |omega0| overflows)")
        period = self._orbit[_kernels.SLOT_PERIOD]
        if scaled.size and math.isfinite(period) and period > 0.0:
            # the elliptic argument u = u0 + rate t keeps its quarter-period
            # count exact only below 2^52 quarters: beyond, the place within
            # the period is lost to rounding (and the count's parity with it)
            largest = float(np.max(np.abs(scaled)))
            if largest > TIME_LIMIT_PERIODS * period:
                raise InputError(
                    f"|t| = {largest / period:.3g} periods is beyond the "
                    f"{TIME_LIMIT_PERIODS:.3g} periods (2^50) at which a double still "
                    "places a time within its period: the orientation there is lost to "
                    "rounding"
                )
        return times, np.ascontiguousarray(scaled.reshape(-1))

    def check_times(self, t):
        """Raise :class:`~orbits.InputError` now for times ``t`` the motion cannot place.

        The check of :meth:`state` (and of every method that takes times),
        without computing anything: a time not finite, or ``|t|`` beyond
        ``2**50`` periods.  An animation checks its frames' span with it
        before it draws.

        Parameters
        ----------
        t : float or array_like
            Times, in the time unit of ``omega0``.
        """
        self._times(t)

    @size_aware
    def state(self, t):
        """Everything at the times ``t``: a :class:`MotionState`.

        Every method that takes times (``omega``, ``euler_angles``,
        ``rotation``, ``quaternion``, ...) takes them here.

        Parameters
        ----------
        t : float or array_like
            Times since the start, in the time unit of ``omega0`` (s for
            rad/s); any shape, negative times included.

        Raises
        ------
        InputError
            A time not finite, or ``|t|`` beyond ``2**50`` periods, where a
            double no longer places a time within its period (the
            orientation there is lost to rounding).

        Notes
        -----
        A double time ``t`` is itself rounded by ``eps |t|``, so the
        orientation at ``t`` cannot be better than about ``eps |omega| t``
        radians (``eps = 2.2e-16``): the error grows linearly with ``t``,
        measured at 0.3 to 2.1 ``eps |omega| t`` (the largest entry of the
        rotation matrix's error) from 1e3 to 2**50 periods against an
        independent integration and an mpmath reduction of the double
        ``t``, about 1e-3 rad at 1e12 periods and of order 1 rad near
        2**49.  No warning says so below the ``2**50`` refusal.
        """
        times, flat = self._times(t)
        n = flat.shape[0]
        omega = np.empty((n, 3))
        euler = np.empty((n, 3))
        rotation = np.empty((n, 3, 3))
        omega_space = np.empty((n, 3))
        _grid_kernels.motion_on_grid(self._orbit, flat, True, omega, euler, rotation, omega_space)
        shape = times.shape
        omega = _scaled(omega, self._speed, "angular velocity")
        omega_space = _scaled(omega_space, self._speed, "angular velocity")
        return MotionState(
            np.array(times, dtype=float),  # a copy: not the caller's array
            omega.reshape(shape + (3,)),
            euler.reshape(shape + (3,)),
            rotation.reshape(shape + (3, 3)),
            omega_space.reshape(shape + (3,)),
        )

    def omega(self, t):
        """Body-frame angular velocity, shape ``t.shape + (3,)``: (3,) for a scalar t."""
        return self.state(t).omega

    def angular_momentum(self, t):
        """Body-frame angular momentum ``I omega`` (the polhode), shape ``t.shape + (3,)``."""
        unit = np.ldexp(self.state(t).omega, -self._speed) * self.body.unit_moments
        return _scaled(unit, self._speed + self.body.exponent, "angular momentum")

    def euler_angles(self, t):
        """Euler angles ``(phi, theta, psi)``, z-x'-z'', radians, shape ``t.shape + (3,)``."""
        return self.state(t).euler

    def rotation(self, t):
        """Orientation matrices (body -> space), shape ``t.shape + (3, 3)``."""
        return self.state(t).rotation

    def quaternion(self, t):
        """Orientation as unit quaternions ``(w, x, y, z)`` (scalar first), continuous in t.

        Shape ``t.shape + (4,)``.  SciPy's order is scalar last: use
        :meth:`rotation_object` to hand the orientation to SciPy.
        """
        euler = self.state(t).euler
        phi, theta, psi = euler[..., 0], euler[..., 1], euler[..., 2]
        half = 0.5 * theta
        plus = 0.5 * (phi + psi)
        minus = 0.5 * (phi - psi)
        return np.stack(
            [
                np.cos(half) * np.cos(plus),
                np.sin(half) * np.cos(minus),
                np.sin(half) * np.sin(minus),
                np.cos(half) * np.sin(plus),
            ],
            axis=-1,
        )

    @size_aware
    def omega_space(self, t):
        """Space-frame angular velocity (z along M): the herpolhode, shape ``t.shape + (3,)``."""
        times, flat = self._times(t)
        out = np.empty((times.size, 3))
        _grid_kernels.omega_space_on_grid(self._orbit, flat, True, out)
        return _scaled(out, self._speed, "angular velocity").reshape(times.shape + (3,))

    def total_phase(self):
        """``Delta alpha`` from the Euler angle phi after one period.

        ``phi(T) - 2 pi`` on SAM, ``phi(T)`` on LAM (eqn:alphaproto), with
        Carlson's Pi: an evaluation independent of the ``cel`` of
        :func:`orbits.total_phase`.  Accurate to a few ulps for every body,
        thin rods ``(e, 1, 1 + e)`` included (see the module notes).
        """
        return float(_kernels.phase_after_period(self._orbit))

    # -- tumbling periods, as observers of tumbling asteroids give them --
    def tumbling_periods(self):
        """Precession and rotation periods of the non-principal-axis literature.

        Convention of Kaasalainen (2001, A&A 376, 302) and Pravec et al.
        (2005, Icarus 173, 108): Euler angles ``(phi, theta, psi)`` with
        the space z axis along L and the body z axis the short axis I3 on
        SAM, the long axis I1 on LAM.  Then

        * ``P_psi = T`` (eqn:TK): psi, the rotation about that axis, goes
          once round per period of omega in the body (and the nutation
          angle theta twice: ``P_theta = T/2``);
        * ``P_phi = 2 pi T / Delta phi``, the mean precession period of that
          axis about L, where ``Delta phi`` is its azimuth gained per period.
          By eqn:fullphi and eqn:alphaproto, ``Delta phi = Delta alpha + 2 pi``
          on SAM (phi of the I3 axis) and ``Delta phi = Delta alpha - 2 pi`` on
          LAM (the I1 axis: tested against a quadrature of
          ``dphi/dt = L (I2 w2^2 + I3 w3^2)/(I2^2 w2^2 + I3^2 w3^2)``).

        Hence ``P_psi / P_phi = Delta alpha / 2 pi + 1`` (SAM) or ``- 1``
        (LAM): the orbit closes (``Delta alpha = 2 pi p/q``) exactly when
        the period ratio is rational, ``(p + q)/q`` or ``(p - q)/q``.  The
        body's mean rotation about L has period ``2 pi T / Delta alpha``,
        ``1/P_phi - 1/P_psi`` on SAM and ``1/P_phi + 1/P_psi`` on LAM
        (Pravec et al. 2014's strongest lightcurve period P_1 for Apophis).

        On LAM the ratio ``Delta alpha / 2 pi - 1`` is a difference: with
        ``Delta alpha`` within ``delta`` of ``2 pi`` (a thin rod spun near its
        long axis) it keeps about ``eps * 2 pi / delta`` relative accuracy
        (:func:`orbits.spins_with_periods` warns where that exceeds 1e-9).

        Returns
        -------
        TumblingPeriods
            ``precession`` (P_phi), ``rotation`` (P_psi), ``ratio``
            (P_psi/P_phi), ``axis`` (``"short"`` on SAM, ``"long"`` on LAM)
            and ``about_momentum`` (``2 pi T / Delta alpha``), all in the
            time unit of omega0.
        """
        total = self.total_phase()
        turns = total / (2.0 * np.pi)
        sam = self.branch == "SAM"
        ratio = turns + 1.0 if sam else turns - 1.0
        period = float(self.period)
        return TumblingPeriods(
            precession=period / ratio,
            rotation=period,
            ratio=ratio,
            axis="short" if sam else "long",
            about_momentum=period / turns,
        )

    @property
    def precession_period(self):
        """P_phi of :meth:`tumbling_periods`."""
        return self.tumbling_periods().precession

    @property
    def rotation_period(self):
        """P_psi of :meth:`tumbling_periods` (equal to :attr:`period`)."""
        return self.period

    # -- orientation for SciPy ------------------------------------------
    def rotation_object(self, t):
        """The orientation as a :class:`scipy.spatial.transform.Rotation`.

        Body -> space (z along L), as :meth:`rotation`.  SciPy's
        quaternions are scalar-last ``(x, y, z, w)``; :meth:`quaternion`
        here is scalar-first ``(w, x, y, z)``.  A scalar ``t`` gives a
        single rotation, an array one rotation per time (flattened).
        """
        from scipy.spatial.transform import Rotation

        matrices = self.rotation(t)
        if matrices.ndim == 2:
            return Rotation.from_matrix(matrices)
        if matrices.size == 0:
            # SciPy before 1.14 cannot hold an empty stack of rotations
            raise InputError("t is empty: a scipy Rotation needs at least one time")
        return Rotation.from_matrix(matrices.reshape(-1, 3, 3))

    as_scipy = rotation_object

    def __setstate__(self, state):
        self.__dict__.update(state)
        self.omega0.setflags(write=False)  # pickle rebuilds it writeable

    def __repr__(self):
        return (
            f"Motion({self.body!r}, omega0={self.omega0.tolist()}, "
            f"branch={self.branch!r}, period={self.period:.6g})"
        )

    def _repr_html_(self):
        """The motion in a notebook: spin, branch, period, E, |L|, D and the phases."""
        from .units import html_table

        # "kg m^2", or "kg m^2 (lengths in m, mass in kg)" for a solid given
        # in any units: then the energy is in J only under that condition
        unit = self.body.moment_unit
        condition = "" if unit is None else unit[len("kg m^2") :].strip()
        energy_unit, momentum_unit, moment_unit = (
            ("I rad^2/s^2", "I rad/s", "I")
            if unit is None
            else (f"J {condition}".strip(), f"J s {condition}".strip(), unit)
        )
        total = self.total_phase()
        periods = self.tumbling_periods()
        w = self.omega0
        rows = [
            (
                "omega0 (principal axes I1 < I2 < I3)",
                f"({w[0]:.6g}, {w[1]:.6g}, {w[2]:.6g})",
                "rad/s",
            ),
            ("branch", self.branch, "SAM: about I3, LAM: about I1"),
            ("period T (eqn:TK)", self.period, "s"),
            ("omega's I2 part reverses (flip) every T/2", 0.5 * self.period, "s"),
            ("energy E", self.energy, energy_unit),
            ("angular momentum |L|", self.momentum, momentum_unit),
            ("D = M^2 / (2E)", self.D, moment_unit),
            ("elliptic parameter m = k^2", float(self.m), ""),
            ("total phase Delta alpha", total, "rad"),
            ("", total / (2.0 * math.pi), "turns (x 2 pi)"),
            ("P_psi / P_phi (Pravec et al. 2005)", periods.ratio, ""),
            ("P_phi (precession)", periods.precession, "s"),
        ]
        name = f" of {self.body.name!r}" if self.body.name else ""
        return html_table(f"Motion{name} (time in s for omega in rad/s)", rows)


# largest curve returned by herpolhode/polhode (about 0.5 GB of state)
MAX_POINTS = 10_000_000


def _grid(motion, periods, points):
    periods = real_scalar("periods", periods)
    if not (np.isfinite(periods) and periods > 0):
        raise InputError(f"periods must be positive, got {periods}")
    points = integer("points", points, minimum=2, maximum=MAX_POINTS)
    end = periods * motion.period
    if not np.isfinite(end):
        raise InputError(f"periods = {periods!r} periods overflow the time axis")
    return np.linspace(0.0, end, points)


def _paper_motion(body_or_moments, theta, dtheta, phi):
    body = as_body(body_or_moments)
    unit = Body(body.normalized_moments, name=body.name)
    return Motion.from_spin(unit, theta, dtheta=dtheta, phi=phi)


def herpolhode(body_or_moments, theta=None, *, dtheta=None, phi=0.0, periods=1, points=2001):
    """The herpolhode: the angular velocity in the space frame over time.

    Parameters
    ----------
    body_or_moments : Body or array_like, shape (3,)
    theta, dtheta, phi : float
        The initial spin, as in :func:`orbits.total_phase` (``|omega0| = 1``).
    periods : float
        Length of the curve in periods T.
    points : int
        Samples, evenly spaced over ``[0, periods T]``, both ends included.

    Returns
    -------
    t : ndarray, shape (points,)
    omega : ndarray, shape (points, 3)
        Space-frame angular velocity, z along M.  ``omega[:, 2]`` is the
        constant ``2E/M``: the curve lies in the invariable plane and its
        x-y part is the figure.  After one period it is turned by
        ``+Delta alpha`` about z.

    Raises
    ------
    As :func:`orbits.total_phase`; InputError for bad ``periods``/``points``.
    """
    # omega(t) does not depend on the scale of I: no need to normalise
    motion = Motion.from_spin(as_body(body_or_moments), theta, dtheta=dtheta, phi=phi)
    t = _grid(motion, periods, points)
    return t, motion.omega_space(t)


def polhode(body_or_moments, theta=None, *, dtheta=None, phi=0.0, periods=1, points=2001):
    """The polhode: the angular momentum in the body frame over time.

    Parameters as :func:`herpolhode`; ``|I| = 1`` and ``|omega0| = 1``.

    Returns
    -------
    t : ndarray, shape (points,)
    momentum : ndarray, shape (points, 3)
        ``I omega(t)`` in the principal frame; it lies on the sphere
        ``|M| = M`` and the Binet ellipsoid ``M.I^-1.M = 2E``.
    """
    motion = _paper_motion(body_or_moments, theta, dtheta, phi)
    t = _grid(motion, periods, points)
    return t, motion.angular_momentum(t)
