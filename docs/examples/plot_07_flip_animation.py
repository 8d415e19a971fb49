"""
The tennis-racket (Dzhanibekov) flip
====================================

Spun about its intermediate axis, a T-handle (or a tennis racket, or a
phone) does not keep spinning calmly: every half period it turns over.
The spin close to the intermediate axis lies near the separatrix of
Euler's equations; the motion lingers near one orientation, then
swings quickly to the reversed one.  Here the paper's T-handle (8, 4, 1),
spun about its shaft tipped by 0.05 rad: watch the shaft (green axis,
``I2``) reverse in space while L stays fixed.  From the command line::

    orbits animate --preset t-handle --flip --out flip.gif
"""

import numpy as np

from orbits.animate import flip_motion, poinsot_animation

motion = flip_motion(offset=0.05)
print(f"branch {motion.branch}, period T = {motion.period:.3f} (1/|omega0|)")

poinsot = poinsot_animation(motion, periods=1.0, frames=40, fps=10, dpi=96, pyplot=True)
anim = poinsot.animation

# %%
# The flips in numbers: the shaft's direction in space, ``R(t) e2``,
# against the fixed angular momentum (the z axis).  Its component along L
# swings between ``+`` and ``−`` once per half period.
t = np.linspace(0.0, motion.period, 9)
shaft_along_L = motion.rotation(t)[:, 2, 1]
for time, value in zip(t, shaft_along_L):
    print(f"t = {time / motion.period:5.3f} T   shaft . L_hat = {value:+.3f}")
