"""The CUDA path (device="cuda") without a GPU: numba's CUDA simulator.

``NUMBA_ENABLE_CUDASIM=1`` must be set before ``numba.cuda`` is first
imported, so every simulator check runs in a fresh subprocess.  The
simulator runs each GPU thread as Python, so the inputs are small.  The
kernels are the same ``@njit`` scalar functions as the CPU path, so the
simulator checks the launchers, the argument flow and the host side; that
the kernels also compile for real hardware is checked by the ``gpu``-marked
test (skipped without a GPU).
"""

import importlib.util
import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import orbits
from orbits import device as device_module
from orbits.errors import DeviceError

ROOT = Path(__file__).resolve().parents[1]
HAS_NUMBA_CUDA = importlib.util.find_spec("numba_cuda") is not None
needs_numba_cuda = pytest.mark.skipif(
    not HAS_NUMBA_CUDA, reason='numba-cuda not installed (pip install ".[cuda]")'
)


def _run(code, simulator=True):
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    env.pop("NUMBA_ENABLE_CUDASIM", None)
    if simulator:
        env["NUMBA_ENABLE_CUDASIM"] = "1"
    result = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        capture_output=True,
        text=True,
        env=env,
        cwd=ROOT,
        timeout=900,
    )
    assert result.returncode == 0, result.stderr[-3000:]
    return json.loads(result.stdout.strip().splitlines()[-1])


def test_cpu_path_never_imports_cuda():
    out = _run(
        """
        import json, sys
        import orbits
        orbits.total_phase((1.0, 2.0, 2.5), [0.3, 2.0, -7.0])
        orbits.phases((1.0, 2.0, 2.5), [0.3, 1.2])
        print(json.dumps(sorted(m for m in sys.modules if m.startswith(("numba.cuda", "numba_cuda")))))
        """,
        simulator=False,
    )
    assert out == []


def test_unknown_device_is_refused():
    for device in ("gpu", "CUDA", None, 0):
        with pytest.raises(DeviceError, match='device must be "cpu" or "cuda"'):
            orbits.total_phase((1.0, 2.0, 2.5), 0.3, device=device)
    with pytest.raises(DeviceError, match='device must be "cpu" or "cuda"'):
        orbits.phases((1.0, 2.0, 2.5), 0.3, device="tpu")


def test_missing_extra_is_one_line(monkeypatch):
    real = importlib.util.find_spec
    monkeypatch.setattr(
        device_module.importlib.util,
        "find_spec",
        lambda name, *a: None if name == "numba_cuda" else real(name, *a),
    )
    with pytest.raises(DeviceError) as caught:
        orbits.total_phase((1.0, 2.0, 2.5), 0.3, device="cuda")
    message = str(caught.value)
    assert "\n" not in message
    assert 'pip install "orbits[cuda]"' in message


@needs_numba_cuda
def test_no_gpu_is_one_line():
    """Without the simulator and with no usable GPU: DeviceError, not a traceback."""
    out = _run(
        """
        import json
        from unittest import mock
        from numba import cuda
        import orbits
        from orbits import bench
        from orbits.search import search_bodies
        calls = [
            lambda: orbits.total_phase((1.0, 2.0, 2.5), 0.3, device="cuda"),
            lambda: orbits.phases((1.0, 2.0, 2.5), 0.3, device="cuda"),
            lambda: search_bodies([[1.0, 2.0, 2.5]], [10.0], device="cuda"),
            lambda: bench.run(device="cuda"),
        ]
        result = []
        with mock.patch.object(cuda, "is_available", lambda: False):
            for call in calls:
                try:
                    call()
                except orbits.DeviceError as error:
                    result.append(["DeviceError", str(error)])
                else:
                    result.append(["no error", ""])
        print(json.dumps(result))
        """,
        simulator=False,
    )
    assert len(out) == 4
    for kind, message in out:
        assert kind == "DeviceError"
        assert "no usable NVIDIA GPU" in message and "\n" not in message


def test_compile_failure_is_one_line():
    """A numba-cuda that cannot compile beside this NumPy (0.30.4 with NumPy 2.5:
    np.row_stack removed) raises DeviceError with one line."""

    def broken(*args):
        raise AttributeError("module 'numpy' has no attribute 'row_stack'\n  more")

    with pytest.raises(DeviceError) as caught:
        device_module.run_cuda(broken, 1, 2)
    message = str(caught.value)
    assert "\n" not in message
    assert "row_stack" in message and "NumPy" in message
    assert message.endswith("pip install 'numpy<2.5'")


@needs_numba_cuda
def test_compile_failure_in_bench_and_survey_is_one_line(tmp_path):
    """The GPU bench rows and ``orbits survey --device cuda`` with a numba-cuda
    that cannot compile (as on a machine with numba-cuda 0.30.4 beside NumPy
    2.5): exit 2 with one line, and the survey's directory never made."""
    out = _run(
        f"""
        import contextlib, io, json
        from pathlib import Path
        from orbits.cli import main
        from orbits.core import cuda as kernels

        def broken(*args):
            raise AttributeError("module 'numpy' has no attribute 'row_stack'")

        kernels.search_many = kernels.total_phase_kernel_seconds = broken
        result = {{}}
        target = Path({str(tmp_path)!r}) / "survey"
        for name, argv in (
            ("cuda_phase", ["bench", "--device", "cuda", "--only", "cuda_phase", "--quick"]),
            ("cuda_search", ["bench", "--device", "cuda", "--only", "cuda_search", "--quick"]),
            ("survey", ["survey", "--device", "cuda", "--resolution", "6", "--n-max", "3",
                        "--out", str(target)]),
        ):
            err = io.StringIO()
            with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
                try:
                    code = main(argv)
                except SystemExit as stop:
                    code = stop.code
            result[name] = [code, err.getvalue()]
        result["made"] = target.exists()
        print(json.dumps(result))
        """
    )
    assert out.pop("made") is False
    for name, (code, err) in out.items():
        assert code == 2, (name, err)
        lines = err.strip().splitlines()
        assert len(lines) == 1 and "row_stack" in lines[0] and "Traceback" not in err, (name, err)


@needs_numba_cuda
def test_small_launches_do_not_warn_about_occupancy():
    """numba-cuda warns "Grid size 1 will likely result in GPU
    under-utilization" when a kernel is configured with few blocks (seen on
    an H200 for a survey's last chunk); our launches configure without it,
    and other warnings still pass."""
    out = _run(
        """
        import json, warnings
        from orbits.core import cuda as kernels

        class Kernel:
            def __getitem__(self, config):
                warnings.warn("Grid size 1 will likely result in GPU under-utilization due "
                              "to low occupancy.")
                warnings.warn("something else")
                return config

        with warnings.catch_warnings(record=True) as seen:
            warnings.simplefilter("always")
            config = kernels._configured(Kernel(), 130, 64)
        print(json.dumps([list(config), [str(w.message) for w in seen]]))
        """
    )
    assert out == [[3, 64], ["something else"]]


@needs_numba_cuda
def test_total_phase_simulator_matches_cpu():
    """total_phase(device="cuda") within 4 ulps of the CPU path: one body
    (theta to fold, dtheta), many bodies with phi, and the errors."""
    out = _run(
        """
        import json
        import numpy as np
        import orbits
        rng = np.random.default_rng(7)
        body = (1.0, 1.7, 2.3)
        theta = np.concatenate([rng.uniform(-7.0, 7.0, 20), [0.0, np.pi / 2, 1e-9]])
        dtheta = np.concatenate([-np.geomspace(1e-300, 0.5, 8), np.geomspace(1e-300, 0.3, 8)])
        moments = np.array([[1.0, 2.0, 2.5], [0.3, 0.9, 1.1], [2.0, 3.0, 4.5]])
        theta3 = rng.uniform(0.05, 1.5, (4, 3))
        phi3 = rng.uniform(-3.0, 3.0, (4, 3))
        result = {}
        for label, kwargs in [
            ("theta", dict(body_or_moments=body, theta=theta)),
            ("dtheta", dict(body_or_moments=body, dtheta=dtheta)),
            ("phi", dict(body_or_moments=body, theta=theta[:6], phi=0.7)),
            ("many", dict(body_or_moments=moments, theta=theta3, phi=phi3)),
        ]:
            cpu = orbits.total_phase(**kwargs)
            gpu = orbits.total_phase(**kwargs, device="cuda")
            assert gpu.shape == cpu.shape and gpu.dtype == cpu.dtype
            result[label] = [cpu.ravel().tolist(), gpu.ravel().tolist()]
        errors = []
        for kwargs in [dict(theta=[0.2, np.nan]), dict(dtheta=[0.1, 5.0]), dict(theta=1e9)]:
            for device in ("cpu", "cuda"):
                try:
                    orbits.total_phase(body, **kwargs, device=device)
                except orbits.OrbitsError as error:
                    errors.append([device, type(error).__name__, str(error)])
        result["errors"] = errors
        print(json.dumps(result))
        """
    )
    for label in ("theta", "dtheta", "phi", "many"):
        cpu, gpu = (np.array(v) for v in out[label])
        assert np.all(np.isfinite(cpu)) and np.all(cpu >= 2 * np.pi)
        np.testing.assert_array_max_ulp(gpu, cpu, maxulp=4)
    errors = out["errors"]
    assert len(errors) == 6
    for cpu_error, gpu_error in zip(errors[0::2], errors[1::2]):
        assert cpu_error[0] == "cpu" and gpu_error[0] == "cuda"
        assert cpu_error[1:] == gpu_error[1:]


@needs_numba_cuda
def test_phases_simulator_matches_cpu():
    out = _run(
        """
        import json
        import numpy as np
        import orbits
        theta = np.linspace(-3.0, 3.0, 13)
        cpu = orbits.phases((1.0, 1.7, 2.3), theta, 0.4)
        gpu = orbits.phases((1.0, 1.7, 2.3), theta, 0.4, device="cuda")
        assert list(cpu.columns) == list(gpu.columns)
        assert (cpu["branch"] == gpu["branch"]).all()
        numeric = [c for c in cpu.columns if c != "branch"]
        print(json.dumps({c: [cpu[c].tolist(), gpu[c].tolist()] for c in numeric}))
        """
    )
    assert len(out) == 15
    for column, (cpu, gpu) in out.items():
        cpu, gpu = np.array(cpu), np.array(gpu)
        assert np.all(np.isfinite(cpu)), column
        # dtheta on the folded-theta path is exact in both: compare like the rest
        np.testing.assert_array_max_ulp(gpu, cpu, maxulp=4)


@pytest.mark.gpu
@needs_numba_cuda
def test_total_phase_on_hardware():
    """On a real GPU (skips without one): 10^5 angles against the CPU path.

    NVVM contracts ``a * b + c`` into fused multiply-adds, so the bound is
    relative (1e-14), not the simulator's 4 ulps.
    """
    out = _run(
        """
        import json
        from numba import cuda
        if not cuda.is_available():
            print(json.dumps(None))
            raise SystemExit
        import numpy as np
        import orbits
        theta = np.linspace(1e-6, np.pi / 2 - 1e-6, 100_000)
        cpu = orbits.total_phase((1.0, 1.7, 2.3), theta)
        gpu = orbits.total_phase((1.0, 1.7, 2.3), theta, device="cuda")
        print(json.dumps(float(np.max(np.abs(gpu / cpu - 1.0)))))
        """,
        simulator=False,
    )
    if out is None:
        pytest.skip("no NVIDIA GPU")
    assert out < 1e-14


@needs_numba_cuda
def test_search_simulator_matches_cpu():
    """search_bodies(device="cuda") gives the CPU search's rows exactly (the
    simulator runs the same compiled scalar search per thread)."""
    out = _run(
        """
        import json
        import numpy as np
        import orbits
        from orbits.bodies import unit_moments
        from orbits.search import phase_levels, searched
        moments = unit_moments([[1.0, 2.0, 2.5], [0.3, 0.9, 1.1], [2.0, 3.0, 4.5]])[0]
        p, q, values = phase_levels(4, 2)
        levels = values[searched(p, q)]
        cpu = orbits.search_bodies(moments, levels)
        gpu = orbits.search_bodies(moments, levels, device="cuda")
        result = {"counts": [cpu.counts.tolist(), gpu.counts.tolist()]}
        for name in ("branch", "level", "offset"):
            rows = []
            for rows_of in (cpu, gpu):
                a = getattr(rows_of, name)
                rows.append([a[b, : cpu.counts[b]].tolist() for b in range(3)])
            result[name] = rows
        result["info"] = [cpu.info.tolist(), gpu.info.tolist()]
        print(json.dumps(result))
        """
    )
    cpu_counts, gpu_counts = out["counts"]
    assert cpu_counts == gpu_counts
    assert sum(cpu_counts) >= 6 and min(cpu_counts) > 0
    for name in ("branch", "level", "offset", "info"):
        assert out[name][0] == out[name][1], name


def test_search_bodies_cpu_equals_search_many():
    """The entry point's CPU rows are core.search.search_many's."""
    from orbits.bodies import unit_moments
    from orbits.core import search as kernels
    from orbits.search import phase_levels, search_bodies, searched

    moments = np.ascontiguousarray(unit_moments(orbits.region_grid(12))[0])
    p, q, values = phase_levels(6, 2)
    levels = np.ascontiguousarray(values[searched(p, q)])
    rows = search_bodies(moments, levels)
    n, capacity = moments.shape[0], 2 * levels.size + 8
    ref = (
        np.empty((n, capacity), np.int8),
        np.empty((n, capacity), np.int64),
        np.empty((n, capacity)),
        np.empty(n, np.int64),
        np.empty((n, kernels.INFO_SIZE)),
    )
    kernels.search_many(moments, levels, *ref)
    np.testing.assert_array_equal(rows.counts, ref[3])
    assert rows.counts.sum() > 3 * n
    for b in range(n):
        k = rows.counts[b]
        np.testing.assert_array_equal(rows.branch[b, :k], ref[0][b, :k])
        np.testing.assert_array_equal(rows.level[b, :k], ref[1][b, :k])
        np.testing.assert_array_equal(rows.offset[b, :k], ref[2][b, :k])
    np.testing.assert_array_equal(rows.info, ref[4])


def test_search_bodies_refuses_bad_input():
    from orbits.search import search_bodies

    with pytest.raises(orbits.InputError, match="shape"):
        search_bodies(np.ones(3), [10.0])
    with pytest.raises(orbits.InputError, match="ascending order"):
        search_bodies([[1.0, 2.0, 2.5]], [20.0, 10.0])
    with pytest.raises(orbits.InputError, match="strictly ascending"):
        search_bodies([[2.0, 1.0, 2.5]], [10.0])


@needs_numba_cuda
def test_kernels_compile_to_ptx():
    """Every CUDA kernel compiles to PTX for sm_90 (an H100): no Python object,
    allocation or unsupported call in device code.  Needs the CUDA toolkit's
    NVVM and NVRTC libraries but no GPU (numba-cuda asks the device for its
    compute capability, which is given here); skips without the toolkit."""
    out = _run(
        """
        import json, types
        import numba.cuda.dispatcher as dispatcher
        dispatcher.get_current_device = lambda: types.SimpleNamespace(compute_capability=(9, 0))
        from numba import boolean, cuda, float64, int8, int64
        try:
            from orbits.core import cuda as kernels
            one = (float64, float64, float64, float64, float64[::1], boolean, float64)
            many = (float64[::1],) * 5 + (boolean, float64)
            sigs = {
                "_total_phase_one_body_kernel": one + (float64[::1], int8[::1]),
                "_total_phase_many_kernel": many + (float64[::1], int8[::1]),
                "_phases_kernel": many + (float64[:, ::1], int8[::1], int8[::1]),
                "_search_kernel": (
                    float64[:, ::1], float64[::1], int8[:, ::1], int64[:, ::1],
                    float64[:, ::1], int64[::1], float64[:, ::1],
                ),
            }
            sizes = {}
            for name, sig in sigs.items():
                ptx, _ = cuda.compile_ptx(getattr(kernels, name).py_func, sig, cc=(9, 0))
                sizes[name] = len(ptx)
        except Exception as error:
            text = str(error)
            if any(word in text for word in ("libnvvm", "libnvrtc", "NVVM", "libdevice")):
                print(json.dumps(None))
                raise SystemExit
            raise
        print(json.dumps(sizes))
        """,
        simulator=False,
    )
    if out is None:
        pytest.skip("no CUDA toolkit (NVVM/NVRTC) to compile PTX with")
    assert set(out) == {
        "_total_phase_one_body_kernel",
        "_total_phase_many_kernel",
        "_phases_kernel",
        "_search_kernel",
    }
    assert min(out.values()) > 1000


@needs_numba_cuda
def test_bench_rows_under_simulator():
    """The GPU bench rows run end to end (tiny sizes; the simulator's timings
    mean nothing) and report the device, rates and the agreement."""
    out = _run(
        """
        import json
        from orbits import bench
        phase = bench.bench_cuda_total_phase(points=48, repeats=1)
        search = bench.bench_cuda_search(resolution=6, n_max=3, repeats=1)
        print(json.dumps([phase, search]))
        """
    )
    phase, search = out
    for row in out:
        assert row["device"] and row["ours_s"] > 0 and row["baseline_s"] > 0
    assert phase["angles_per_s"] > 0 and "max relative difference" in phase["note"]
    assert search["bodies_per_s"] > 0 and "root counts equal" in search["note"]


@needs_numba_cuda
def test_survey_cli_device_cuda_simulator_writes_the_cpu_orbits(tmp_path):
    """``orbits survey --device cuda --resolution 10 --n-max 4`` (simulator)
    writes the same orbits, in the same files, as the CPU run."""
    out = _run(
        f"""
        import hashlib, json, sys
        from pathlib import Path
        from orbits.cli import main
        from orbits.survey import read_survey
        root = Path({str(tmp_path)!r})
        codes = [
            main(["survey", "--resolution", "10", "--n-max", "4", "--device", device,
                  "--out", str(root / device)])
            for device in ("cpu", "cuda")
        ]
        cpu, gpu = (read_survey(root / device) for device in ("cpu", "cuda"))
        parts = {{}}
        for device in ("cpu", "cuda"):
            parts[device] = {{
                str(p.relative_to(root / device)): hashlib.sha256(p.read_bytes()).hexdigest()
                for p in sorted((root / device).glob("*/part-*"))
            }}
        print(json.dumps({{
            "codes": codes,
            "rows": [len(cpu[1]), len(gpu[1])],
            "equal": bool(cpu[0].equals(gpu[0]) and cpu[1].equals(gpu[1])),
            "parts_equal": parts["cpu"] == parts["cuda"],
            "parts": len(parts["cpu"]),
            "kernels_loaded": "orbits.core.cuda" in sys.modules,
        }}))
        """
    )
    assert out["codes"] == [0, 0]
    assert out["rows"][0] == out["rows"][1] > 0
    assert out["equal"] and out["parts_equal"] and out["parts"] >= 2
    assert out["kernels_loaded"]  # the search did run through orbits.core.cuda


def test_survey_device_cuda_without_a_gpu_is_one_line(tmp_path, capsys):
    """No usable GPU: exit 2 with one line, and nothing written."""
    from orbits.cli import main

    try:
        device_module.cuda_kernels()
    except DeviceError:
        pass
    else:
        pytest.skip("a GPU is usable here")
    target = tmp_path / "s"
    code = main(
        ["survey", "--resolution", "10", "--n-max", "4", "--device", "cuda", "--out", str(target)]
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and err[0].startswith("orbits: error: "), err
    assert not target.exists()
