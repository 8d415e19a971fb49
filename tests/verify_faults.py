"""A wrong closed form for `orbits verify` to find: shared by the tests of
orbits.checks and of the command line."""


def wrong_closed_form(monkeypatch, factor):
    """Make verify's kernel return the closed form (of omega0 and of theta)
    ``factor`` times the true one, as a wrong formula would: every check is
    then compared with a wrong value."""
    from orbits.core import checks as kernel

    original = kernel.check_batch
    columns = [kernel.CHECK_COLUMNS.index(name) for name in ("closed_form", "closed_form_theta")]

    def mutated(moments, theta, phi, ode_rtol, ode_atol, quad_rtol, out):
        original(moments, theta, phi, ode_rtol, ode_atol, quad_rtol, out)
        out[:, columns] *= factor

    monkeypatch.setattr(kernel, "check_batch", mutated)
