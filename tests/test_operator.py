"""DC-FFT convolution against the dense influence matrix."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from railcontact import ElasticPair, Grid, InfluenceOperator, Material, RailContactError
from railcontact.halfspace.influence import coefficients_at
from railcontact.halfspace.operator import HAVE_PYFFTW, influence_operator

FFT_BACKENDS = ["scipy"] + (["pyfftw"] if HAVE_PYFFTW else [])
STEEL = ElasticPair.of(Material(206e9, 0.28))


@pytest.mark.parametrize("backend", FFT_BACKENDS)
@pytest.mark.parametrize("shape", [(1, 7), (5, 5), (16, 9), (32, 20)])
def test_dcfft_equals_dense(backend, shape):
    g = Grid.from_bounds(-2e-3, 3e-3, -1e-3, 1e-3, *shape)
    p = np.random.default_rng(1).uniform(0, 1e9, shape)
    ref = InfluenceOperator(g, STEEL, "z", "dense").apply(p)
    u = InfluenceOperator(g, STEEL, "z", backend).apply(p)
    assert np.max(np.abs(u - ref)) <= 1e-13 * np.max(np.abs(ref))


@pytest.mark.parametrize("backend", FFT_BACKENDS)
def test_block_operator_equals_dense(backend):
    pair = ElasticPair.of(Material(210e9, 0.3), Material(70e9, 0.33))
    g = Grid.from_bounds(0, 1e-3, 0, 2e-3, 11, 8)
    p = np.random.default_rng(2).normal(size=(3, 11, 8))
    ref = InfluenceOperator(g, pair, "xyz", "dense").apply(p)
    u = InfluenceOperator(g, pair, "xyz", backend).apply(p)
    assert np.max(np.abs(u - ref)) <= 1e-13 * np.max(np.abs(ref))


@settings(max_examples=25, deadline=None)
@given(nx=st.integers(1, 12), ny=st.integers(1, 12), aspect=st.floats(0.1, 10.0))
def test_dense_is_the_direct_sum(nx, ny, aspect):
    """The dense matrix is sum_J A(x_I - x_J) p_J written out element by element."""
    g = Grid(nx, ny, 1e-4, 1e-4 * aspect, 0.0, 0.0)
    op = InfluenceOperator(g, STEEL, "z", "dense")
    X, Y = g.mesh()
    p = np.random.default_rng(nx * 13 + ny).uniform(size=(nx, ny))
    direct = np.zeros((nx, ny))
    for i in range(nx):
        for j in range(ny):
            direct += p[i, j] * coefficients_at("zz", X - X[i, j], Y - Y[i, j], g.dx, g.dy,
                                                STEEL)
    assert np.allclose(op.apply(p), direct, rtol=1e-12, atol=0)


def test_cache_returns_same_operator():
    a = influence_operator(Grid(8, 8, 1e-4, 1e-4, 0, 0), STEEL, "z", "scipy")
    b = influence_operator(Grid(8, 8, 1e-4, 1e-4, 5e-3, -1e-3), STEEL, "z", "scipy")
    assert a is b


def test_bad_backend_and_shape():
    g = Grid(4, 4, 1e-4, 1e-4, 0, 0)
    with pytest.raises(RailContactError, match="fft backend"):
        InfluenceOperator(g, STEEL, "z", "cufft")
    with pytest.raises(RailContactError, match="shape"):
        InfluenceOperator(g, STEEL, "z", "dense").apply(np.zeros((3, 4)))


@pytest.mark.skipif(not HAVE_PYFFTW, reason="pyfftw not installed")
def test_fft_plans_are_bounded_and_a_dropped_plan_is_made_again():
    """More grid shapes than MAX_PLANS keep at most MAX_PLANS plans (memory stays bounded
    in a time series of changing patches); an operator whose plan was dropped plans again
    and still equals the dense product."""
    import railcontact.halfspace.operator as operator_module

    g = Grid.from_bounds(-2e-3, 3e-3, -1e-3, 1e-3, 6, 5)
    op = InfluenceOperator(g, STEEL, "z", "pyfftw")
    p = np.random.default_rng(3).uniform(0, 1e9, (6, 5))
    ref = InfluenceOperator(g, STEEL, "z", "dense").apply(p)
    first = op.apply(p)
    for k in range(operator_module.MAX_PLANS + 3):
        operator_module._fftw_plan(1, (4, 2 * k + 2), 2)
    plans = operator_module._local.plans
    assert len(plans) == operator_module.MAX_PLANS and (1, (12, 10), 6) not in plans
    again = op.apply(p)  # its plan was dropped: planned anew (estimated: same bits)
    assert np.max(np.abs(again - ref)) <= 1e-13 * np.max(np.abs(ref))
    assert np.array_equal(again, first)


def test_fft_sizes_are_the_smallest_5_smooth_numbers():
    """fft_size(n): the smallest 2^a 3^b 5^c >= n (checked by brute force)."""
    from railcontact.halfspace.operator import fft_size, padded_shape

    def smooth(m):
        for f in (2, 3, 5):
            while m % f == 0:
                m //= f
        return m == 1

    for n in range(1, 400):
        m = fft_size(n)
        assert m >= n and smooth(m) and not any(smooth(k) for k in range(n, m))
    assert padded_shape(38, 59) == (80, 120)


@pytest.mark.parametrize("backend", FFT_BACKENDS)
@pytest.mark.parametrize("shape", [(7, 11), (19, 13), (38, 59)])
def test_padding_to_5_smooth_sizes_keeps_the_convolution_exact(backend, shape):
    """Grids whose doubled counts are not 5-smooth (14 -> 15, 22 -> 24, 38 -> 40, 118 ->
    120, ...) still give the dense (exact) product, for one and for two components."""
    nx, ny = shape
    g = Grid.from_bounds(-2e-3, 2e-3, -3e-3, 3e-3, nx, ny)
    rng = np.random.default_rng(nx * ny)
    for comps in ("z", "xy"):
        p = rng.uniform(-1e9, 1e9, (len(comps), nx, ny))
        fast = InfluenceOperator(g, STEEL, comps, backend).apply(p)
        ref = InfluenceOperator(g, STEEL, comps, "dense").apply(p)
        assert np.max(np.abs(fast - ref)) <= 1e-12 * np.max(np.abs(ref))


@pytest.mark.skipif(not HAVE_PYFFTW, reason="pyfftw not installed")
def test_wisdom_saved_and_loaded_gives_the_same_product(tmp_path):
    """save_wisdom measures the plans of small grids; after load_wisdom an operator planned
    from it gives the dense product; a file that is not wisdom is a clear error."""
    import railcontact.halfspace.operator as operator_module

    path = tmp_path / "wisdom.txt"
    assert operator_module.save_wisdom(path, max_elements=6) > 0
    operator_module.load_wisdom(path)
    g = Grid.from_bounds(-1e-3, 1e-3, -1e-3, 1e-3, 5, 6)
    p = np.random.default_rng(5).uniform(0, 1e9, (5, 6))
    fast = InfluenceOperator(g, STEEL, "z", "pyfftw").apply(p)
    ref = InfluenceOperator(g, STEEL, "z", "dense").apply(p)
    assert np.max(np.abs(fast - ref)) <= 1e-12 * np.max(np.abs(ref))
    bad = tmp_path / "bad.txt"
    bad.write_text("not wisdom")
    with pytest.raises(RailContactError, match="wisdom"):
        operator_module.load_wisdom(bad)


@pytest.mark.skipif(not HAVE_PYFFTW, reason="pyfftw not installed")
def test_grids_sharing_a_padded_shape_do_not_mix():
    """45 x 45 and 41 x 41 grids share the padded shape 90 x 90 (and its plan and buffers):
    a product on the smaller grid after one on the larger is still the dense product."""
    rng = np.random.default_rng(7)
    out = []
    for n in (45, 41):
        g = Grid.from_bounds(-2e-3, 2e-3, -2e-3, 2e-3, n, n)
        p = rng.uniform(0, 1e9, (n, n))
        fast = InfluenceOperator(g, STEEL, "z", "pyfftw").apply(p)
        ref = InfluenceOperator(g, STEEL, "z", "dense").apply(p)
        out.append(np.max(np.abs(fast - ref)) / np.max(np.abs(ref)))
    assert max(out) <= 1e-12


@pytest.mark.skipif(not HAVE_PYFFTW, reason="pyfftw not installed")
def test_a_bad_wisdom_file_is_a_clear_error(tmp_path):
    """Review finding: a file holding a tuple of the wrong length made pyfftw raise an
    IndexError through load_wisdom (and through the import, with RAILCONTACT_FFTW_WISDOM)."""
    import railcontact.halfspace.operator as operator_module

    for text in ("(b'x',)", "[1, 2, 3]", "(b'a', b'b', 3)"):
        bad = tmp_path / "bad.txt"
        bad.write_text(text)
        with pytest.raises(RailContactError, match="wisdom"):
            operator_module.load_wisdom(bad)
    with pytest.raises(RailContactError, match="max_elements"):
        operator_module.save_wisdom(tmp_path / "w.txt", max_elements=0)


@pytest.mark.skipif(not HAVE_PYFFTW, reason="pyfftw not installed")
@pytest.mark.parametrize("comps", ["z", "xy", "xyz"])
def test_pruned_products_of_grids_sharing_a_plan_stay_exact(comps):
    """Grids with the same row count and padded shape share one pruned plan (19 x 20 and
    19 x 19 both pad to 40 x 40): the narrower grid's product after the wider one (and
    back) still equals the dense product - the column the wider grid wrote is cleared;
    for the one-component (normal), two-component (tangential) and three-component products."""
    from railcontact.halfspace.operator import padded_shape

    rng = np.random.default_rng(11)
    products = []
    for ny in (20, 19, 20):
        g = Grid.from_bounds(-2e-3, 2e-3, -3e-3, 3e-3, 19, ny)
        p = rng.uniform(-1e9, 1e9, (len(comps), 19, ny))
        fast = InfluenceOperator(g, STEEL, comps, "pyfftw").apply(p)
        ref = InfluenceOperator(g, STEEL, comps, "dense").apply(p)
        products.append(np.max(np.abs(fast - ref)) / np.max(np.abs(ref)))
    assert padded_shape(19, 20) == padded_shape(19, 19)
    assert max(products) <= 1e-12


@pytest.mark.parametrize("backend", FFT_BACKENDS + ["dense"])
def test_bound_products_are_the_operator_and_its_preconditioner(backend):
    """A solve's products as bound functions (``InfluenceOperator.bound``) write the dense
    influence matrix's product into the buffer given, and with a floor the FFT
    preconditioner's (the same values as ``preconditioner()``), for repeated calls."""
    g = Grid.from_bounds(-2e-3, 3e-3, -1e-3, 1e-3, 17, 12)
    rng = np.random.default_rng(4)
    op = InfluenceOperator(g, STEEL, "z", backend)
    dense = InfluenceOperator(g, STEEL, "z", "dense").dense()
    product, inverse = op.bound(), op.bound(1e-2)
    apply_inverse = op.preconditioner(1e-2)
    out = np.empty(g.shape)
    for _ in range(3):
        p = rng.uniform(0, 1e9, g.shape)
        ref = (dense @ p.ravel()).reshape(g.shape)
        assert product(p, out) is out
        assert np.max(np.abs(out - ref)) <= 1e-13 * np.max(np.abs(ref))
        r = rng.normal(size=g.shape) * 1e-6
        assert np.array_equal(inverse(r, out), apply_inverse(r))
    two = InfluenceOperator(g, STEEL, "xy", backend)  # two components, strided input
    dense2 = InfluenceOperator(g, STEEL, "xy", "dense").dense()
    product2 = two.bound()
    q = rng.uniform(-1e8, 1e8, (2, g.ny, g.nx)).transpose(0, 2, 1)
    ref2 = (dense2 @ np.ascontiguousarray(q).ravel()).reshape(2, *g.shape)
    assert np.max(np.abs(product2(q, None) - ref2)) <= 1e-13 * np.max(np.abs(ref2))
    with pytest.raises(RailContactError, match="one-component"):
        InfluenceOperator(g, STEEL, "xy", backend).bound(1e-2)


@pytest.mark.skipif(not HAVE_PYFFTW, reason="pyfftw not installed")
@pytest.mark.parametrize("shape", [(1, 5), (7, 6), (12, 9), (13, 16), (20, 33)])
def test_products_of_kernels_without_symmetry_equal_dense(shape):
    """The FFTW products (complex-packed: ``p_x + i p_y``, or one component's rows in
    pairs, which pair each wave number with its negative) for kernels that are neither
    even nor reciprocal (random, and the steady-rolling difference kernels): the dense
    product of the same kernels, for even and odd row counts and padded sizes (7 rows pad
    to 15, the one-component pruned plan)."""
    from railcontact.tangential.rolling import steady_rolling_kernels

    nx, ny = shape
    g = Grid.from_bounds(-2e-3, 2e-3, -3e-3, 3e-3, nx, ny)
    rng = np.random.default_rng(nx * 31 + ny)
    rolling = steady_rolling_kernels(nx, ny, g.dx, g.dy, STEEL)
    for k in (rng.normal(size=(1, 1, 2 * nx - 1, 2 * ny - 1)),
              rng.normal(size=(2, 2, 2 * nx - 1, 2 * ny - 1)), rolling):
        comps = "xy"[:k.shape[0]] if k.shape[0] == 2 else "z"
        p = rng.uniform(-1e9, 1e9, (k.shape[0], nx, ny))
        fast = InfluenceOperator(g, STEEL, comps, "pyfftw", kernels=k)
        ref = InfluenceOperator(g, STEEL, comps, "dense", kernels=k).apply(p)
        scale = np.max(np.abs(ref))
        assert np.max(np.abs(fast.apply(p) - ref)) <= 1e-13 * scale
        out = np.empty(p.shape if k.shape[0] == 2 else p.shape[1:])
        product = fast.bound()
        for _ in range(2):  # the bound product, repeated (its buffers reused)
            assert product(p if k.shape[0] == 2 else p[0], out) is out
            assert np.max(np.abs(out - (ref if k.shape[0] == 2 else ref[0]))) <= 1e-13 * scale


def _fresh_python(code: str) -> str:
    """What ``code`` prints, run in a fresh interpreter (imports as at a process's start)."""
    import subprocess
    import sys

    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True).stdout


def test_import_leaves_out_pyfftws_dask_interface():
    """``import railcontact`` does not import dask.array through pyfftw's interfaces (about
    a second at every FMU instance's start); pyfftw's dask interface still imports after."""
    code = ("import sys, railcontact.halfspace.operator as op\n"
            "assert op.HAVE_PYFFTW == (op.pyfftw is not None)\n"
            "print('dask.array' in sys.modules, 'dask.array.fft' in sys.modules)\n"
            "import pyfftw.interfaces.dask_fft\n"
            "print(sys.modules['dask.array.fft'] is not None)\n")
    assert _fresh_python(code).split() == ["False", "False", "True"]


def test_import_of_pyfftw_leaves_other_threads_imports_of_dask_array_alone():
    """While railcontact imports pyfftw without its dask interface,
    another thread's ``import dask.array`` (a dask worker's) is not refused. The other
    thread imports dask.array exactly while pyfftw is imported (a hook on that import
    waits for it)."""
    import importlib.util

    if importlib.util.find_spec("dask") is None:
        pytest.skip("dask not installed")
    code = (
        "import builtins, threading\n"
        "import dask\n"
        "errors = []\n"
        "def other():\n"
        "    try:\n"
        "        import dask.array\n"
        "    except Exception as exc:\n"
        "        errors.append(repr(exc))\n"
        "thread = threading.Thread(target=other)\n"
        "real = builtins.__import__\n"
        "def hooked(name, *args, **kwargs):\n"
        "    if name == 'pyfftw' and not thread.is_alive() and thread.ident is None:\n"
        "        thread.start()\n"
        "        thread.join()\n"
        "    return real(name, *args, **kwargs)\n"
        "builtins.__import__ = hooked\n"
        "import railcontact.halfspace.operator as op\n"
        "builtins.__import__ = real\n"
        "assert thread.ident is not None and op.HAVE_PYFFTW\n"
        "print(errors or 'ok')\n")
    assert _fresh_python(code).strip() == "ok"


@pytest.mark.skipif(not HAVE_PYFFTW, reason="pyfftw not installed")
@pytest.mark.parametrize("nc, nx, shape", [(1, 7, (16, 30)), (1, 20, (40, 64)),
                                           (2, 9, (18, 24)), (2, 32, (64, 128))])
def test_a_compiled_product_is_pyfftws_product_bit_for_bit(monkeypatch, nc, nx, shape):
    """The DC-FFT product run as one compiled call (FFTW's plans made and executed through
    its C interface) gives pyfftw's product to the last bit: the plans are made with the
    same dimensions, strides and flags, so FFTW picks the same algorithm (a step repeated
    with or without the compiled path stays the same). Shapes with a row stride padded
    against cache-set conflicts (128 columns) included."""
    from railcontact.halfspace import operator as op

    if not op._fftw.AVAILABLE:
        pytest.skip("FFTW's C interface not found next to pyfftw")
    rng = np.random.default_rng(nx)
    m, n = shape
    spectra = (rng.normal(size=(nc, nc, m, n // 2 + 1))
               + 1j * rng.normal(size=(nc, nc, m, n // 2 + 1)))
    operands = op._packed_operands(spectra, shape)
    compiled = op._PackedPlan(nx, shape, nc=nc)
    monkeypatch.setattr(op._fftw, "AVAILABLE", False)
    executes = op._PackedPlan(nx, shape, nc=nc)
    assert compiled.compiled and not executes.compiled
    for ny in (n // 2 - 3, n // 2):  # grids of two widths on one plan
        p = rng.normal(size=((nc,) if nc == 2 else ()) + (nx, ny))
        a, b = compiled.convolve(operands, p, None), executes.convolve(operands, p, None)
        assert a.tobytes() == b.tobytes()
