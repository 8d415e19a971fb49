"""
Catalogs of closed orbits, and how to read them
===============================================

A catalog lists every spin of a body (``φ = 0``, ``|ω₀| = 1``) whose total
phase is a rational number of turns, ``Δα = 2πp/q``: after ``q`` periods
the body is back at its starting orientation and its herpolhode closes.
``orbits catalog`` writes one as CSV; here we make one in Python, write it,
read it back and look at what its columns say.
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import orbits

# %%
# Make, write, read
# -----------------
# The paper's Fig. 6 body, integer orbits ``n ≤ 12`` and fractions with
# ``q ≤ 3``.  :func:`orbits.write_catalog` writes atomically, with a
# provenance header (version, command, row count, SHA-256 of the data);
# :func:`orbits.read_catalog` checks all of it and the schema.
body = orbits.Body.preset("fig6")
table = orbits.closed_orbits(body, n_max=12, q_max=3)

path = Path(tempfile.mkdtemp()) / "fig6.csv"
orbits.write_catalog(table, path, command="gallery example")
print("".join(path.read_text().splitlines(keepends=True)[:7]))
catalog = orbits.read_catalog(path)
assert catalog.equals(table)  # floats read back bit for bit

# %%
# The columns
# -----------
# One row per closed orbit, sorted by θ.  ``n`` and ``q`` give the level
# ``Δα = 2πn/q`` (``n`` is the numerator ``p`` when ``q > 1``);
# ``residual`` is ``Δα − 2πn/q`` (at most 1e-10 of it, in practice a few
# ulps).  ``closes_after`` is in periods: the herpolhode closes after
# ``q/2`` periods when ``p`` and ``q`` are both odd, else after ``q`` (the
# body itself needs the full ``q``).
columns = [
    "branch",
    "n",
    "q",
    "closes_after",
    "theta",
    "dtheta",
    "total_phase",
    "geometric_phase",
    "period",
    "residual",
]
print(catalog[catalog.q == 1][columns].to_string(max_rows=30))

# %%
# ``theta`` or ``dtheta``?
# ------------------------
# The orbits crowd geometrically towards the separatrix θ_c: Δα grows like
# ``log(1/|θ − θ_c|)``, so each ``n`` is ≈ 6.3× closer to θ_c than the last.
# ``theta`` is a double near 1, so it holds ``θ − θ_c`` only to an absolute
# 1e-16: at ``n = 12`` (``|dθ| ≈ 5e-10``) that is 7 digits, and by
# ``n ≈ 20`` none at all.  The column ``dtheta = θ − θ_c`` carries the
# orbit at full relative precision.  Always rebuild a spin from ``dtheta``:
row = catalog[(catalog.n == 12) & (catalog.q == 1) & (catalog.branch == "SAM")].iloc[0]
print(f"theta = {row.theta:.17g}, theta_c = {row.theta_crit:.17g}, dtheta = {row.dtheta:.17g}")
print("Delta alpha / 2 pi from theta :", orbits.total_phase(body, row.theta) / (2 * np.pi))
print("Delta alpha / 2 pi from dtheta:", orbits.total_phase(body, dtheta=row.dtheta) / (2 * np.pi))

# %%
# The same picture as a plot: ``|dθ|`` of the integer orbits against ``n``
# falls on two straight lines on a log scale, one per branch.
integer = catalog[catalog.q == 1]
fig, ax = plt.subplots(figsize=(6.4, 4.0), layout="constrained")
for branch, marker in (("SAM", "o"), ("LAM", "s")):
    rows = integer[integer.branch == branch]
    ax.semilogy(rows.n, np.abs(rows.dtheta), marker, label=branch)
    slope = np.polyfit(rows.n[rows.n >= 4], np.log(np.abs(rows.dtheta[rows.n >= 4])), 1)[0]
    print(f"{branch}: |dtheta| shrinks by {np.exp(-slope):.2f}x per n")
ax.set_xlabel("multiple n  (Δα = 2πn)")
ax.set_ylabel("|θ − θ_c|  (rad)")
ax.set_title("Closed orbits of the Fig. 6 body approach the separatrix geometrically")
ax.legend()

# %%
# Fractions ``p/q``
# -----------------
# With ``--q-max`` the catalog also holds orbits that close after several
# periods.  Each ``q`` adds levels between the integers.  On a log scale of
# ``|θ − θ_c|`` the SAM branch's ``Δα`` is nearly a straight line, and the
# orbits sit on it wherever it crosses a level ``p/q``.
fig, ax = plt.subplots(figsize=(6.4, 4.2), layout="constrained")
offsets = -np.logspace(-11, np.log10(body.critical_angle() - 0.3), 400)
ax.semilogx(-offsets, orbits.total_phase(body, dtheta=offsets) / (2 * np.pi), color="0.5")
sam = catalog[catalog.branch == "SAM"]
for q, marker in ((1, "o"), (2, "^"), (3, "s")):
    rows = sam[sam.q == q]
    ax.plot(-rows.dtheta, rows.total_phase / (2 * np.pi), marker, ms=5, label=f"q = {q}")
ax.invert_xaxis()
ax.set_xlabel("θ_c − θ (rad), SAM branch")
ax.set_ylabel("Δα / 2π")
ax.set_title("SAM orbits with Δα = 2πp/q, q ≤ 3")
ax.legend()

# %%
# With ``verify=True`` (CLI ``--verify``) :func:`orbits.catalog` adds
# ``closure_error``: the angle by which the orientation after ``q`` periods
# misses the start, from an independent integration of Euler's equations.
checked = orbits.catalog([body], n_max=4, verify=True)
print(checked[["branch", "n", "theta", "closure_error"]])
plt.show()
