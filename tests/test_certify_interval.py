"""The outward-rounded interval kernels (kernels/interval.py, kernels/certify.py's Krawczyk step)
against python-flint's arb balls: the ball of the exact result always lies inside the interval."""

from __future__ import annotations

import math

import numpy as np
import flint  # the test extra installs it (pyproject.toml): never skipped
import pytest

from cdpr_design.kernels import certify as KC  # noqa: E402
from cdpr_design.kernels import interval as I  # noqa: E402
from tests.reference.interval import idot

arb = flint.arb
N = 3000


@pytest.fixture(autouse=True)
def _precision():
    old = flint.ctx.prec
    flint.ctx.prec = 300  # sums and products of doubles come out exact (balls of radius 0)
    yield
    flint.ctx.prec = old


def _floats(rng, k, positive=False):
    """Random doubles over many magnitudes, with exact ties, zeros and near-ulp neighbours."""
    x = rng.uniform(1, 2, k) * 2.0 ** rng.integers(-40, 40, k)
    if not positive:
        x *= rng.choice([-1.0, 1.0], k)
    x[rng.random(k) < 0.03] = 0.0
    near = rng.random(k) < 0.1
    x[near] = np.nextafter(1.0, 2.0) * rng.choice([1.0, 3.0, 0.1], near.sum())
    return x


def _intervals(rng, k, positive=False):
    a = _floats(rng, k, positive)
    b = np.where(rng.random(k) < 0.3, a, _floats(rng, k, positive))  # a third are points
    return np.minimum(a, b), np.maximum(a, b)


def _holds(lo, hi, exact) -> bool:
    """Every point of the arb ball ``exact`` lies in [lo, hi]."""
    return bool(arb(lo) <= exact) and bool(exact <= arb(hi))


@pytest.mark.parametrize("op", ["add", "sub", "mul", "div"])
def test_binary_operations_enclose_the_exact_range(op):
    rng = np.random.default_rng(hash(op) % 2**32)
    al, ah = _intervals(rng, N)
    bl, bh = _intervals(rng, N)
    f = {"add": I.iadd, "sub": I.isub, "mul": I.imul, "div": I.idiv}[op]
    exact = {"add": lambda a, b: a + b, "sub": lambda a, b: a - b, "mul": lambda a, b: a * b,
             "div": lambda a, b: a / b}[op]
    tight = 0
    for k in range(N):
        lo, hi = f(al[k], ah[k], bl[k], bh[k])
        if op == "div" and bl[k] <= 0.0 <= bh[k]:
            assert (lo, hi) == (-math.inf, math.inf)
            continue
        for a in (al[k], ah[k]):
            for b in (bl[k], bh[k]):
                assert _holds(lo, hi, exact(arb(a), arb(b))), (op, al[k], ah[k], bl[k], bh[k], lo, hi)
        if al[k] == ah[k] and bl[k] == bh[k]:  # points in: a few ulps wide, not anything that holds
            tight += 1
            assert hi - lo <= 4 * np.spacing(max(abs(lo), abs(hi))) + 1e-300
    assert tight > N // 20


def test_square_sqrt_abs_enclose_the_exact_range():
    rng = np.random.default_rng(1)
    al, ah = _intervals(rng, N)
    for k in range(N):
        lo, hi = I.isqr(al[k], ah[k])
        a, b = arb(al[k]), arb(ah[k])
        assert _holds(lo, hi, a * a) and _holds(lo, hi, b * b)
        if al[k] <= 0 <= ah[k]:
            assert lo == 0.0
        lo, hi = I.iabs(al[k], ah[k])
        assert _holds(lo, hi, abs(a)) and _holds(lo, hi, abs(b))
    pl, ph = _intervals(rng, N, positive=True)
    for k in range(N):
        lo, hi = I.isqrt(pl[k], ph[k])
        assert _holds(lo, hi, arb(pl[k]).sqrt()) and _holds(lo, hi, arb(ph[k]).sqrt())


def test_dot_encloses_every_product_sum():
    rng = np.random.default_rng(2)
    for _ in range(300):
        n = int(rng.integers(1, 9))
        al, ah = _intervals(rng, n)
        bl, bh = _intervals(rng, n)
        lo, hi = idot(al, ah, bl, bh)
        for _ in range(4):  # random corners: the exact range is reached at corners
            a = np.where(rng.random(n) < 0.5, al, ah)
            b = np.where(rng.random(n) < 0.5, bl, bh)
            s = sum((arb(x) * arb(y) for x, y in zip(a, b)), arb(0))
            assert _holds(lo, hi, s)


def test_unit_component_encloses_the_unit_vector_over_the_box():
    rng = np.random.default_rng(3)
    for _ in range(2000):
        c = rng.normal(size=3) * 10.0 ** rng.integers(-3, 2)
        w = np.abs(rng.normal(size=3)) * 10.0 ** rng.integers(-4, 0)
        lo3, hi3 = c - w, c + w
        sq = [I.isqr(lo3[i], hi3[i]) for i in range(3)]
        rl, rh = I.iadd(sq[1][0], sq[1][1], sq[2][0], sq[2][1])
        lo, hi = I.unit_component(lo3[0], hi3[0], rl, rh)
        assert -1.0 <= lo <= hi <= 1.0
        for _ in range(6):
            p = [arb(v) for v in rng.uniform(lo3, hi3)]
            corner = [arb(v) for v in np.where(rng.random(3) < 0.5, lo3, hi3)]
            for q in (p, corner):
                norm = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt()
                assert _holds(lo, hi, q[0] / norm)


def test_krawczyk_encloses_every_solution_of_the_interval_system():
    rng = np.random.default_rng(4)
    proven = 0
    for _ in range(300):
        n = int(rng.integers(2, 7))
        A = rng.normal(size=(n, n)) + 3 * np.eye(n)
        b = rng.normal(size=n)
        ra = np.abs(rng.normal(size=(n, n))) * 10.0 ** rng.integers(-8, -1)
        rb = np.abs(rng.normal(size=n)) * 10.0 ** rng.integers(-8, -1)
        Al, Ah, bl, bh = A - ra, A + ra, b - rb, b + rb
        Xl, Xh = np.empty(n), np.empty(n)
        scratch = [np.empty((n, n)) for _ in range(4)] + [np.empty(n) for _ in range(3)]
        ok = KC.krawczyk(Al, Ah, bl, bh, scratch[0], scratch[1], scratch[4], scratch[2], scratch[3],
                         scratch[5], scratch[6], Xl, Xh, np.empty((n, 2 * n)))
        if not ok:
            continue
        proven += 1
        for _ in range(5):
            M = rng.uniform(Al, Ah)
            v = rng.uniform(bl, bh)
            x = flint.arb_mat(M.tolist()).solve(flint.arb_mat([[float(t)] for t in v]))
            for i in range(n):
                assert _holds(Xl[i], Xh[i], x[i, 0])
    assert proven > 200


def _arb_column(a, b, p, rows):
    """[u ; b x u] restricted to ``rows`` in arb, u = (a - b - p)/|a - b - p|; and du/dp_k."""
    d = [arb(float(a[i])) - arb(float(b[i])) - arb(float(p[i])) for i in range(3)]
    L = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
    u = [x / L for x in d]
    B = [arb(float(x)) for x in b]

    def rows_of(v):
        full = v + [B[1] * v[2] - B[2] * v[1], B[2] * v[0] - B[0] * v[2], B[0] * v[1] - B[1] * v[0]]
        return [full[r] for r in rows]

    derivs = [rows_of([-((1 if c == k else 0) - u[c] * u[k]) / L for c in range(3)]) for k in range(3)]
    return rows_of(u), derivs


def test_structure_matrix_and_its_derivative_enclose_every_point_of_the_box():
    rng = np.random.default_rng(6)
    rows = np.array([0, 1, 2, 3, 4, 5], dtype=np.int64)
    for _ in range(60):
        m = int(rng.integers(2, 9))
        A = rng.uniform(-3, 3, (m, 3))
        B = rng.uniform(-0.3, 0.3, (m, 3))
        c = rng.uniform(-1, 1, 3)
        w = np.abs(rng.normal(size=3)) * 10.0 ** rng.integers(-4, 0)
        plo, phi = c - w, c + w
        Wl, Wh = np.empty((6, m)), np.empty((6, m))
        U, L = np.empty((m, 3, 2)), np.empty((m, 2))
        ok = KC.interval_structure(plo, phi, A, A, B, B, rows, Wl, Wh, U, L)
        D = [(np.empty((6, m)), np.empty((6, m))) for _ in range(3)]
        for k in range(3):
            KC.structure_derivative(k, U, L, B, B, rows, D[k][0], D[k][1], np.empty((3, 2)))
        for _ in range(5):
            p = rng.uniform(plo, phi)
            for j in range(m):
                col, derivs = _arb_column(A[j], B[j], p, rows)
                for i in range(6):
                    assert _holds(Wl[i, j], Wh[i, j], col[i])
                    if ok:
                        for k in range(3):
                            assert _holds(D[k][0][i, j], D[k][1][i, j], derivs[k][i])


def _arb_matrix(A, B, p, rows):
    """The structure matrix (len(rows), m) in arb at the position ``p`` (3,) for the outlets ``A`` and
    rotated attachments ``B`` (m, 3)."""
    cols = [_arb_column(A[j], B[j], p, rows)[0] for j in range(A.shape[0])]
    return [[cols[j][i] for j in range(A.shape[0])] for i in range(len(rows))]


def _random_case(rng, rows):
    """A box of positions and a geometry with random tolerances, about an IPAnema-like 8-cable layout
    (or a planar one for 3 rows), as the kernels take them (:class:`KC.Box`, :class:`KC.Geometry`)."""
    m = int(rng.integers(len(rows), 9))
    if len(rows) == 6:
        corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], float)
        pick = rng.permutation(8)[:m]
        Ac = corners[pick] * [2.0, 1.5, 1.0] + [0, 0, 1.0] + rng.normal(0, 0.1, (m, 3))
        Bc = corners[pick][:, [1, 0, 2]] * [0.6, 0.15, 0.3] + rng.normal(0, 0.03, (m, 3))
        c = rng.uniform([-0.5, -0.4, 0.7], [0.5, 0.4, 1.3])
        plane = 3
    else:  # planar: z = 0 everywhere
        ang = np.sort(rng.uniform(0, 2 * np.pi, m))
        Ac = np.stack([2 * np.cos(ang), 1.5 * np.sin(ang), np.zeros(m)], axis=1)
        Bc = np.stack([0.15 * np.cos(ang + rng.normal(0, 0.5, m)), 0.1 * np.sin(ang), np.zeros(m)], axis=1)
        c = np.array([*rng.uniform(-0.4, 0.4, 2), 0.0])
        plane = 2
    half = np.zeros(3)
    half[:plane] = 10.0 ** rng.uniform(-3.5, -1.3, plane)
    mask = np.array([1.0, 1.0, 1.0 if plane == 3 else 0.0])
    ta = 10.0 ** rng.uniform(-4, -2, (m, 1)) * (rng.random((m, 1)) < 0.8) * mask
    tb = 10.0 ** rng.uniform(-4, -2, m) * (rng.random(m) < 0.8)
    if plane == 3:  # a random rotation of the attachments' errors (effector coordinates)
        Re = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    else:
        a = rng.uniform(-np.pi, np.pi)
        Re = np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 0.0]])
    rb = np.nextafter((np.abs(Re) @ mask)[None, :] * tb[:, None] * (1 + 1e-12), np.inf)
    P = KC.Box(c - half, c + half, c.copy())
    G = KC.Geometry(Ac - ta, Ac + ta, Bc - rb, Bc + rb, Ac, Bc, np.asarray(rows, dtype=np.int64), Re, tb)
    return P, G


def _sample(rng, lo, hi):
    """A random point of the box [lo, hi], or (one time in four) a random corner of it."""
    return np.where(rng.random(lo.shape) < 0.5, lo, hi) if rng.random() < 0.25 else rng.uniform(lo, hi)


def _attachments(rng, G):
    """Rotated attachments within the tolerance: B_j = Bc_j + Re e, e in [-tb_j, tb_j]^3 (a random
    point, or one time in four a corner, of each cable's cube)."""
    e = _sample(rng, -np.repeat(G.tb[:, None], 3, 1), np.repeat(G.tb[:, None], 3, 1))
    return G.Bc + e @ G.Re.T


@pytest.mark.parametrize("rows", [(0, 1, 2, 3, 4, 5), (0, 1, 5)])
def test_mean_value_form_encloses_the_basis_tensions_at_every_pose_and_geometry(rows):
    """The centred forms in every outlet and attachment coordinate at the box's centre
    (kernels/certify.py's centre_enclosure), then in the position (mean_value): at the centre and
    at random poses of random boxes, with random geometries within random tolerances and random
    wrenches within the margin, the exact basis tensions (arb) lie in the enclosures; and the
    refined one is never wider than the first-order one it refines."""
    import itertools

    rng = np.random.default_rng(7 + len(rows))
    n = len(rows)
    refined = checked = 0
    for _ in range(120):
        P, G = _random_case(rng, rows)
        m = G.Ac.shape[0]
        bases = np.array(list(itertools.combinations(range(m), n)), dtype=np.int64)
        facets = np.array(list(itertools.combinations(range(m), n - 1)), dtype=np.int64)
        T = KC.Task(rng.normal(0, 50, (1, n)), np.zeros(m), np.full(m, 1e3), float(rng.choice([0.0, 2.0])),
                    facets, bases)
        basis = int(rng.integers(bases.shape[0]))
        t = rng.uniform(0, 400, m)
        scr = KC.make_scratch(n, m)
        E = scr.box
        KC.interval_structure(P.lo, P.hi, G.Alo, G.Ahi, G.Blo, G.Bhi, G.rows, E.Wl, E.Wh, E.U, E.L)
        if not KC.basis_enclosure(E.Wl, E.Wh, T, basis, t, T.wv[0], E.Al, E.Ah, E.bl, E.bh, scr.kr, E.Xl, E.Xh):
            continue
        first = (E.Xl.copy(), E.Xh.copy())
        if not KC.centre_enclosure(P, G, T, basis, t, T.wv[0], scr):
            continue
        centre = (E.Tl.copy(), E.Th.copy())
        if not KC.mean_value(P, G, T, basis, t, scr):
            continue
        refined += 1
        assert np.all(E.Xl >= first[0]) and np.all(E.Xh <= first[1])
        b = list(bases[basis])
        fixed = [j for j in range(m) if j not in b]
        for at_centre in (True, False, False, False, False):
            p = P.c if at_centre else _sample(rng, P.lo, P.hi)
            e = rng.uniform(-T.mu, T.mu, n)
            W = _arb_matrix(_sample(rng, G.Alo, G.Ahi), _attachments(rng, G), p, rows)
            rhs = [arb(float(T.wv[0, i])) + arb(float(e[i]))
                   - sum((W[i][j] * arb(float(min(max(t[j], 0.0), 1e3))) for j in fixed), arb(0))
                   for i in range(n)]
            x = flint.arb_mat([[W[i][j] for j in b] for i in range(n)]).solve(flint.arb_mat([[v] for v in rhs]))
            lo, hi = centre if at_centre else (E.Xl, E.Xh)
            for q in range(n):
                assert _holds(lo[q], hi[q], x[q, 0]), (at_centre, q, lo[q], hi[q], x[q, 0])
            checked += 1
    assert refined > 40 and checked > 160


@pytest.mark.parametrize("rows", [(0, 1, 2, 3, 4, 5), (0, 1, 5)])
def test_centred_gap_bounds_the_support_gap_at_every_pose_and_geometry(rows):
    """The centred form of the outside test's support gap (kernels/certify.py's centred_gap), in the
    position and in every outlet and attachment coordinate: an upper bound of the exact gap (arb)
    at random poses of random boxes with random geometries within random tolerances."""
    rng = np.random.default_rng(17 + len(rows))
    n = len(rows)
    bounded = 0
    for _ in range(150):
        P, G = _random_case(rng, rows)
        m = G.Ac.shape[0]
        scr = KC.make_scratch(n, m)
        E = scr.box
        KC.interval_structure(P.lo, P.hi, G.Alo, G.Ahi, G.Blo, G.Bhi, G.rows, E.Wl, E.Wh, E.U, E.L)
        nu = rng.normal(size=n)
        nu /= np.linalg.norm(nu)
        tmid = rng.uniform(50, 500, m)
        rho = tmid * rng.uniform(0.2, 1.0, m)
        w = rng.normal(0, 300, n)
        bound = KC.centred_gap(P, G, nu, tmid, rho, w, E)
        if not np.isfinite(bound):
            continue
        bounded += 1
        for _ in range(4):
            W = _arb_matrix(_sample(rng, G.Alo, G.Ahi), _attachments(rng, G), _sample(rng, P.lo, P.hi), rows)
            lj = [sum((arb(float(nu[i])) * W[i][j] for i in range(n)), arb(0)) for j in range(m)]
            gap = sum((arb(float(tmid[j])) * lj[j] for j in range(m)), arb(0)) \
                - sum((arb(float(nu[i])) * arb(float(w[i])) for i in range(n)), arb(0))
            s = sum((arb(float(rho[j])) * abs(lj[j]) for j in range(m)), arb(0)) - abs(gap)
            assert bool(s <= arb(bound)), (s, bound)
    assert bounded > 60


def test_python_flint_is_a_test_dependency_only():
    """The interval kernels' reference is needed by the tests alone: a user's install does not pull
    it in (was a runtime dependency), and certifying works without it."""
    import subprocess
    import sys
    import tomllib
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    project = tomllib.loads((root / "pyproject.toml").read_text())["project"]
    assert not [d for d in project["dependencies"] if d.startswith("python-flint")]
    assert [d for d in project["optional-dependencies"]["test"] if d.startswith("python-flint")]
    code = ("import sys; sys.modules['flint'] = None\n"  # an import of flint would fail
            "import cdpr_design as cd\n"
            "r = cd.certify(cd.load('designs/planar2.yaml'), resolution=0.3)\n"
            "print(r.counts()['inside'])")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=root, timeout=600,
                       env={**__import__("os").environ, "PYTHONPATH": str(root)})
    assert r.returncode == 0 and int(r.stdout) > 0, r.stderr
