"""
The tennis-racket (Dzhanibekov) flip
====================================

Spun about its intermediate axis, a T-handle (or a tennis racket, or a
phone) does not keep spinning calmly: every half period it turns over.
The spin close to the intermediate axis lies near the separatrix of
Euler's equations; the motion lingers near one orientation, then
swings quickly to the reversed one.  Here the paper's T-handle (8, 4, 1),
spun about its shaft tipped 0.05 rad towards each of the other two axes
(``flip_motion``: ω₀ ∝ (sin 0.05 cos 0.05, cos² 0.05, sin 0.05), 0.0707 rad
from the shaft): watch the shaft (green axis, ``I2``) reverse in space
while L stays fixed.  From the command line::

    orbits animate --preset t-handle --flip --out flip.gif

Run as a plain script (``python plot_07_flip_animation.py``), it plays the
animation in a window, or without a display writes it to a GIF.
"""

import sys
import tempfile
from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt
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

# %%
# Outside this gallery (which embeds the animation itself), show it: in a
# window with an interactive matplotlib backend, else as a GIF file.
if "sphinx_gallery" not in sys.modules:
    if matplotlib.get_backend().lower() == "agg":
        print("written:", poinsot.save(Path(tempfile.mkdtemp()) / "flip.gif"))
    else:
        plt.show()
