"""
Poinsot's construction in motion
================================

Poinsot's picture of the free top: the body's inertia ellipsoid
``x·I·x = 1`` rolls without slipping on the *invariable plane*, the plane
perpendicular to the fixed angular momentum L at distance ``√(2E)/M`` from
the centre.  The contact point is ``ω/√(2E)``: it lies on the
instantaneous axis of rotation, so it is at rest.  On the ellipsoid it
traces the polhode (body frame); on the plane, the herpolhode (space
frame).

Below, a closed orbit of the paper's Fig. 6 body, ``Δα = 2π·4`` on the
short-axis branch: after one period the body is back at its starting
orientation, and the herpolhode (purple) closes at its start (dot).  Left:
space frame, L up; right: body frame.  The command line writes the same
animation as a GIF (or an MP4 with imageio-ffmpeg)::

    orbits animate --preset fig6 --n 4 --branch SAM --out fig6_n4.gif

Run as a plain script (``python plot_06_poinsot_animation.py``), it plays
the animation in a window, or without a display writes it to a GIF.
"""

import sys
import tempfile
from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt
import numpy as np

import orbits
from orbits.animate import orbit_row, poinsot_animation

body = orbits.Body.preset("fig6")
row = orbit_row(body, n=4, branch="SAM")
print(row[["branch", "n", "theta", "dtheta", "period", "closes_after"]])

# %%
# ``pyplot=True`` creates the figure through pyplot (for notebooks and this
# gallery); ``.animation`` is a matplotlib ``FuncAnimation``.  Keep it in
# a variable, or it is garbage-collected before it plays.
poinsot = poinsot_animation(row, frames=36, fps=10, dpi=96, pyplot=True)
anim = poinsot.animation

# %%
# The drawn data of each frame are exact: the orientation at frame ``k`` is
# :meth:`orbits.Motion.rotation` at its time, and the contact point is on
# the plane and on the rotated ellipsoid.
last = poinsot.frame(len(poinsot.times) - 1)
first = poinsot.frame(0)
print(
    "orientation after one period - start:", f"{np.abs(last.rotation - first.rotation).max():.1e}"
)
print("contact height - plane height:", f"{last.contact[2] - last.plane_height:.1e}")

# %%
# Outside this gallery (which embeds the animation itself), show it: in a
# window with an interactive matplotlib backend, else as a GIF file.
if "sphinx_gallery" not in sys.modules:
    if matplotlib.get_backend().lower() == "agg":
        print("written:", poinsot.save(Path(tempfile.mkdtemp()) / "fig6_n4.gif"))
    else:
        plt.show()
