"""The cffi kernel loader and the EFMM C kernels called directly on one triangle."""

import numpy as np
import pytest

from geofrac import kernels


@pytest.fixture
def fresh_efmm(tmp_path, monkeypatch):
    """The efmm kernel compiled from source into an empty cache."""
    monkeypatch.setenv("GEOFRAC_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(kernels, "_LOADED", {})
    module = kernels.load("efmm")
    assert list((tmp_path / "kernels").glob("efmm-*/_efmm*.so"))
    return module


def _call(module, name, size, w, c, x):
    ffi = module.ffi
    A = np.zeros(size)
    getattr(module.lib, name)(
        ffi.from_buffer("double[]", A),
        ffi.from_buffer("double[]", w),
        ffi.from_buffer("double[]", c),
        ffi.from_buffer("double[]", x),
        ffi.NULL,
        ffi.NULL,
        ffi.NULL,
    )
    return A


def test_kernels_integrate_node_moments_that_sum_to_the_cell(fresh_efmm):
    x = np.array([0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 1.0, 0.0])  # area 1
    p = np.array([0.5, 0.3])
    X = np.array([[1.0, 0.5], [0.0, 0.5], [1.0, 0.0]])  # on the edge opposite each vertex
    w = np.concatenate([p, X.ravel()])
    Dinv = np.array([[1.0, -0.2, 0.0], [-0.2, 1.0, 0.0], [0.0, 0.0, 2.4]]) / 1000.0
    c = np.concatenate([Dinv.ravel(), [1.0]])
    mass = _call(fresh_efmm, "efmm_stress_mass", 3 * 81, w, c, x).reshape(3, 9, 9)
    # the (1, 1) moment of each node's part is its area; the parts tile the cell
    areas = mass[:, 0, 0] / Dinv[0, 0]
    assert areas.sum() == pytest.approx(1.0, abs=1e-14)
    assert np.all(areas > 0)
    # A_j = D⁻¹ ⊗ M_j: block (a, b) is D⁻¹[a, b] times the same moment matrix
    for j in range(3):
        M = mass[j, :3, :3] / Dinv[0, 0]
        assert np.allclose(mass[j, 3:6, 0:3], Dinv[1, 0] * M, rtol=0, atol=1e-17)
        assert np.allclose(M, M.T, rtol=0, atol=1e-16)
    coupling = _call(fresh_efmm, "efmm_coupling", 27 * 6, w, c, x).reshape(27, 6)
    # rows (node, σx, 1) summed over nodes: ∫_T B row εx = area * dN/dx
    total = coupling[[0, 9, 18]].sum(axis=0)
    assert np.allclose(total, [-0.5, 0.0, 0.5, 0.0, 0.0, 0.0], rtol=0, atol=1e-14)
    # a rigid translation has no strain: C u = 0
    assert np.abs(coupling @ np.tile([1.0, 0.0], 3)).max() < 1e-15


def test_a_broken_compiler_is_a_clear_error(tmp_path, monkeypatch):
    monkeypatch.setenv("GEOFRAC_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv("CC", str(tmp_path / "no-such-compiler"))
    monkeypatch.setattr(kernels, "_LOADED", {})
    with pytest.raises(RuntimeError, match="compiling the efmm kernel failed"):
        kernels.load("efmm")


_NUMBA_PROBE = """
import sys
{first}
import geofrac
sys.path.insert(0, sys.argv[1])
import jitted
assert jitted.twice(21) == 42
import numba
print(numba.config.CACHE_DIR)
"""


@pytest.mark.parametrize("numba_first", [False, True])
def test_numba_cache_goes_to_the_user_cache_not_the_package(tmp_path, numba_first):
    """A cached jitted function's files land in geofrac's cache, none beside its source."""
    import os
    import subprocess
    import sys

    source = tmp_path / "src"
    source.mkdir()
    (source / "jitted.py").write_text(
        "import numba\n\n@numba.njit(cache=True)\ndef twice(x):\n    return 2 * x\n"
    )
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env["GEOFRAC_CACHE_DIR"] = str(tmp_path / "cache")
    code = _NUMBA_PROBE.format(first="import numba" if numba_first else "")
    done = subprocess.run(
        [sys.executable, "-c", code, str(source)],
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == str(tmp_path / "cache" / "numba")
    assert list((tmp_path / "cache" / "numba").rglob("*.nbi"))
    beside = [p for p in source.rglob("*") if p.suffix in (".nbi", ".nbc")]
    assert beside == []


def test_numba_cache_dir_set_by_the_user_is_kept(tmp_path):
    import os
    import subprocess
    import sys

    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "mine"))
    code = "import geofrac, numba; print(numba.config.CACHE_DIR)"
    done = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=False
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == str(tmp_path / "mine")
