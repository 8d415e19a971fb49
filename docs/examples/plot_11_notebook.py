"""
In a notebook
=============

Every object of ``orbits`` that a notebook shows as the value of a cell
has an HTML view (``_repr_html_``) with its units, and a one-line
``repr`` for the console.  This page is such a notebook: each cell's last
expression is displayed as Jupyter would.

A phone (71 x 147 x 7.8 mm, 170 g), thrown at 120 rpm about its short
edge, with a little wobble: the tennis-racket flip.
"""

import numpy as np

import orbits

phone = orbits.Body.box(0.071, 0.147, 0.0078, 0.17, name="phone")
phone

# %%
# The throw, in the phone's own axes (x along the 71 mm edge), in rpm;
# ``axes="body"`` says so (:attr:`orbits.Body.frame` turns it to the
# principal axes ``I1 < I2 < I3``).
rpm = 2 * np.pi / 60
throw = np.array([120.0, 2.0, 1.0]) * rpm
motion = orbits.Motion.from_omega(phone, throw, axes="body")
motion

# %%
# Its periods as an asteroid observer gives them (Pravec et al. 2005).
motion.tumbling_periods()

# %%
# The smallest total phase the phone can have, at either end of
# ``0 < theta < pi/2``.
orbits.phase_limits(phone)

# %%
# The three closed orbits nearest the throw, each started at its
# angular momentum ``|L|`` near its direction: ``omega_x, omega_y,
# omega_z`` in rpm in the phone's own axes, ``period_s`` in seconds.
nearest = orbits.nearest_orbits(phone, [120.0, 2.0, 1.0], 3, units="rpm")
nearest[["branch", "n", "q", "total_phase", "omega_x", "omega_y", "omega_z", "period_s"]]

# %%
# The closed form against independent checks on a few bodies and spins.
orbits.verify(n_bodies=3, n_angles=2)

# %%
# The throw in motion, one period in real time at 20 frames per second (at
# 2 turns a second the phone turns about 36 degrees a frame; at 6 frames a
# second it would turn 120, and an AliasingWarning would say so):
# the player below is the animation's own HTML view, shown once.  Its
# figure is drawn off-screen (the default ``pyplot=False``), so no static
# copy of it appears; built with ``pyplot=True``, the view closes the
# figure once the player is made, for the same effect in Jupyter.
orbits.poinsot_animation(motion, seconds=motion.period, fps=20, dpi=60)
