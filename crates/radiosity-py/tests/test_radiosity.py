"""The Python bindings against closed forms, NumPy and the CLI."""

import csv
import os
import pathlib
import subprocess

import numpy as np
import pytest

import radiosity

REPO = pathlib.Path(__file__).resolve().parents[3]
FURNACE_RHO = np.array([0.3, 0.5, 0.7])


def test_furnace_closed_form():
    # Every surface emits 1 and reflects ρ in a closed box: B = E / (1 − ρ). Gathering by rows
    # (Jacobi), whose Monte Carlo estimates each sum to 1 exactly in a closed box, has that
    # as its fixed point for any such F: exact up to the tolerance.
    s = radiosity.solve(radiosity.builtin("furnace"), solver="jacobi", patches=500, tolerance=1e-9)
    assert s.info["converged"]
    expected = 1.0 / (1.0 - FURNACE_RHO)
    assert np.allclose(s.radiosity, expected, rtol=1e-6)
    assert s.areas.shape == (s.radiosity.shape[0],)
    assert s.centres.shape == s.normals.shape == s.radiosity.shape


def test_hierarchical_furnace():
    # Hierarchical radiosity on the furnace: its leaves' area-weighted mean is E / (1 − ρ) to
    # 0.2 % and every leaf within 15 % (the receiver-side error, measured up to 10 % in blue,
    # where ρ = 0.7 amplifies it most).
    assert "hierarchical" in radiosity.methods()["scene_solvers"]
    s = radiosity.solve(radiosity.builtin("furnace"), solver="hierarchical", tolerance=1e-8)
    expected = 1.0 / (1.0 - FURNACE_RHO)
    mean = (s.radiosity * s.areas[:, None]).sum(axis=0) / s.areas.sum()
    assert np.allclose(mean, expected, rtol=2e-3)
    assert np.all(np.abs(s.radiosity / expected - 1.0) < 0.15)
    with pytest.raises(ValueError, match="link error"):
        radiosity.solve(radiosity.builtin("furnace"), solver="hierarchical", link_error=0.0)


def random_reciprocal(n, seed):
    # F_ij = A_j G_ij with G symmetric, rows scaled to sum below 1: reciprocal and
    # diagonally dominant (the papers' row-dominant random systems).
    rng = np.random.default_rng(seed)
    area = rng.uniform(0.5, 2.0, n)
    g = rng.uniform(0.0, 1.0, (n, n))
    g = (g + g.T) / 2
    np.fill_diagonal(g, 0.0)
    f = g * area[None, :]
    f /= f.sum(axis=1).max() * 1.05
    rho = rng.uniform(0.1, 0.9, (n, 3))
    e = np.zeros((n, 3))
    e[: n // 10 + 1] = rng.uniform(0.5, 2.0, (n // 10 + 1, 3))
    return f, area, rho, e


DETERMINISTIC = [s for s in radiosity.methods()["solvers"] if not s.startswith("stochastic")]


def test_every_deterministic_solver_is_listed():
    assert len(DETERMINISTIC) == 10


@pytest.mark.parametrize("solver", DETERMINISTIC)
def test_solve_system_matches_numpy(solver):
    f, area, rho, e = random_reciprocal(60, 7)
    b, trace = radiosity.solve_system(f, area, rho, e, solver=solver, tolerance=1e-10)
    for c in range(3):
        exact = np.linalg.solve(np.eye(60) - rho[:, c, None] * f, e[:, c])
        # F is stored in f32: the solution is exact for the rounded matrix.
        assert np.allclose(b[:, c], exact, rtol=1e-5, atol=1e-7), solver
    assert trace is not None and len(trace["iteration"]) > 0
    assert np.all(np.isfinite(trace["error"]))


def test_solve_system_takes_scipy_sparse():
    sp = pytest.importorskip("scipy.sparse", reason="SciPy is installed by .ci/run")
    f, area, rho, e = random_reciprocal(40, 3)
    b_dense, _ = radiosity.solve_system(f, area, rho, e, solver="gauss", trace=False)
    b_sparse, t = radiosity.solve_system(sp.csr_matrix(f), area, rho, e, solver="gauss", trace=False)
    assert t is None
    assert np.array_equal(b_dense, b_sparse)


def box(size=1.0):
    # A closed cube, faces wound inward, the top face emitting.
    v = np.array([[x, y, z] for z in (0, size) for y in (0, size) for x in (0, size)], dtype=float)
    # Wound so that each normal (v1 − v0) × (v2 − v0) points into the box.
    faces = np.array(
        [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
    )
    rho = np.full(6, 0.5)
    e = np.zeros(6)
    e[1] = 1.0
    return v, faces, rho, e


def test_from_arrays_round_trip():
    v, faces, rho, e = box(2.0)
    scene = radiosity.Scene.from_arrays(v, faces, rho, e)
    assert scene.polygons == 6
    s = radiosity.solve(scene, patches=600, tolerance=1e-6)
    # Every face is 2 × 2; the patches tile it.
    assert np.isclose(s.areas.sum(), 24.0, rtol=1e-5)
    per_face = np.bincount(s.surfaces, weights=s.areas, minlength=6)
    assert np.allclose(per_face, 4.0, rtol=1e-5)
    # Closed box: the emitted power is absorbed.
    info = s.info
    assert abs(info["absorbed"] + info["unshot"] - info["emitted"]) < 1e-6 * info["emitted"]
    # The faces' inward normals.
    assert np.allclose(np.linalg.norm(s.normals, axis=1), 1.0, atol=1e-6)


def test_stochastic_jacobi_times_its_rays_within_its_solve():
    s = radiosity.solve(radiosity.builtin("cornell"), solver="stochastic-jacobi", patches=2000, tolerance=0.05)
    info = s.info
    assert 0.0 < info["seconds_solve_rays"] <= info["seconds_solve"]
    p = radiosity.solve(radiosity.builtin("cornell"), solver="progressive", patches=500, tolerance=0.05)
    assert p.info["seconds_solve_rays"] == 0.0
    # The final gathering iteration only when asked for: it gathers every patch's B again.
    g = radiosity.solve(
        radiosity.builtin("cornell"), solver="stochastic-jacobi", patches=2000, tolerance=0.05, gather_rays=16
    )
    assert not np.array_equal(g.radiosity, s.radiosity)
    assert g.info["seconds_solve_rays"] > 0.0


def test_bad_input_raises_value_error_naming_the_argument():
    v, faces, rho, e = box()
    with pytest.raises(ValueError, match="vertices"):
        radiosity.Scene.from_arrays(v[:, :2], faces, rho, e)
    with pytest.raises(ValueError, match="reflectance"):
        radiosity.Scene.from_arrays(v, faces, np.full(6, 1.0), e)
    with pytest.raises(ValueError, match="emission"):
        radiosity.Scene.from_arrays(v, faces, rho, np.zeros(5))
    with pytest.raises(ValueError, match="faces"):
        radiosity.Scene.from_arrays(v, faces + 10, rho, e)
    f, area, rho3, e3 = random_reciprocal(10, 1)
    with pytest.raises(ValueError, match="reflectance"):
        radiosity.solve_system(f, area, np.full(10, 1.5), e3)
    with pytest.raises(ValueError, match="F: shape"):
        radiosity.solve_system(f[:5], area, rho3, e3)
    with pytest.raises(ValueError, match="solver"):
        radiosity.solve(radiosity.builtin("furnace"), solver="nope")
    with pytest.raises(ValueError, match="not a built-in scene"):
        radiosity.builtin("nope")


def cli():
    exe = os.environ.get("RADIOSITY_BIN", str(REPO / "target" / "release" / "radiosity"))
    if not pathlib.Path(exe).exists():
        pytest.fail(f"the CLI binary {exe} is missing: build it (cargo build --release) or set RADIOSITY_BIN")
    return exe


def test_same_numbers_as_the_cli(tmp_path):
    out = tmp_path / "c.csv"
    subprocess.run(
        [cli(), "solve", "cornell", "--patches", "800", "--seed", "5", "--out", str(out)],
        check=True,
        capture_output=True,
    )
    with open(out) as fh:
        rows = list(csv.DictReader(fh))
    cli_b = np.array([[float(r[f"radiosity_{c}"]) for c in "rgb"] for r in rows])
    s = radiosity.solve(radiosity.builtin("cornell"), patches=800, seed=5)
    assert s.radiosity.shape == cli_b.shape
    # The CSV holds shortest round-trip decimals: equal to the bit.
    assert np.array_equal(s.radiosity, cli_b)


def test_form_factors_rows_and_reciprocity():
    v, faces, rho, e = box()
    scene = radiosity.Scene.from_arrays(v, faces, rho, e)
    f, areas = radiosity.form_factors(scene, method="analytic", faces=True, with_areas=True)
    dense = f.toarray() if hasattr(f, "toarray") else None
    assert dense is not None, "SciPy is installed by .ci/run"
    # A cube's faces: opposite 0.1998248957, adjacent 0.2000437761 (Howell).
    assert np.allclose(dense.sum(axis=1), 1.0, atol=1e-6)
    assert np.isclose(dense[0, 1], 0.1998248957, atol=1e-6)
    assert np.allclose(areas[:, None] * dense, (areas[:, None] * dense).T, atol=1e-6)


def test_render_and_progress():
    seen = []
    s = radiosity.solve(radiosity.builtin("furnace"), patches=300, tolerance=1e-6)
    img = s.render(16, 12, integrator="gather", spp=4, progress=lambda st, d, t: seen.append(st))
    assert img.shape == (12, 16, 3) and img.dtype == np.float32
    exact = 1.0 / (np.pi * (1.0 - FURNACE_RHO))
    assert np.allclose(img.reshape(-1, 3).mean(axis=0), exact, rtol=0.02)
    assert "render" in seen


def test_an_interrupt_stops_a_long_solve():
    # A solve that would run for minutes (a 1e-12 tolerance on 20,000 patches) stops at the
    # first report after the callback raises, and the exception comes out.
    import time

    calls = []

    def interrupt(stage, done, total):
        calls.append(stage)
        if stage == "solve" and done > 10:
            raise KeyboardInterrupt("stop")

    t = time.perf_counter()
    with pytest.raises(KeyboardInterrupt):
        radiosity.solve(radiosity.builtin("cornell"), patches=20000, tolerance=1e-12, progress=interrupt)
    assert time.perf_counter() - t < 30
    assert "solve" in calls


def test_method_parameters_reach_the_solver():
    with pytest.raises(ValueError, match="ω|omega"):
        radiosity.solve(radiosity.builtin("furnace"), solver="sor", omega=2.5, patches=100)


SIGMA = 5.670374419e-8


def test_thermal_black_cube_and_the_cli_example():
    # View3D's unit cube, every face black at its own temperature: Q_i = Σ_j F_ij σ(T_i⁴ − T_j⁴)
    # with Howell's exact factors (opposite 0.1998248957, adjacent 0.2000437761).
    cube = radiosity.load(str(REPO.parent / "shared" / "scenes" / "view3d" / "cube.vs3"))
    names = ["zeq0", "xeq0", "yeq0", "zeq1", "xeq1", "yeq1"]
    t = [300.0, 400.0, 500.0, 600.0, 700.0, 800.0]
    r = radiosity.thermal(
        cube,
        {n: {"emissivity": 1.0, "temperature": tt} for n, tt in zip(names, t)},
        form_factor_method="analytic",
    )
    opposite = [3, 4, 5, 0, 1, 2]
    for i, n in enumerate(names):
        q = sum(
            (0.1998248957 if opposite[i] == j else 0.2000437761) * SIGMA * (t[i] ** 4 - t[j] ** 4)
            for j in range(6)
            if j != i
        )
        assert abs(r["surfaces"][n]["flux"] - q) < 1e-6 * SIGMA * 800**4
    assert r["info"]["balance_error"] < 1e-9
    # Grey faces: the Jacobi sweeps (the method that runs over MPI ranks) agree with LU.
    grey = {n: {"emissivity": 0.5, "temperature": tt} for n, tt in zip(names, t)}
    lu = radiosity.thermal(cube, grey, form_factor_method="analytic", linear_solver="direct")
    jac = radiosity.thermal(cube, grey, form_factor_method="analytic", linear_solver="jacobi")
    assert jac["info"]["method"] == "jacobi"
    for n in names:
        assert jac["surfaces"][n]["flux"] == pytest.approx(lu["surfaces"][n]["flux"], rel=1e-9, abs=1e-6)
    # The README's hot plate from its bc.csv, as the CLI reports it.
    ex = REPO / "examples"
    r = radiosity.thermal(radiosity.load(str(ex / "hot-plate.obj")), str(ex / "hot-plate-bc.csv"))
    assert abs(r["surfaces"]["plate"]["flux"] - 5800.370612334273) < 1e-6 * 5800
    assert r["surfaces"]["floor"]["flux"] == pytest.approx(0.0, abs=1e-9)
    with pytest.raises(ValueError, match="unknown surface 'nope'"):
        radiosity.thermal(cube, {"nope": {"temperature": 300.0}})
    with pytest.raises(ValueError, match="not both"):
        radiosity.thermal(cube, {"zeq0": {"temperature": 300.0, "flux": 1.0}})


def lightmap_quad_means(m, k):
    # The area mean of the lightmap over input polygon k: the texels whose centre lies inside
    # it (a midpoint rule), over every atlas.
    total, n = np.zeros(3), 0
    for atlas, surface, inside in zip(m["atlases"], m["surface"], m["inside"]):
        t = (surface == k) & inside
        total += atlas[t].sum(axis=0)
        n += t.sum()
    return total / n


def test_bake_lightmap_matches_the_solution():
    # The Cornell box's lightmap (texel 8, 1.4 % of the box) against the solution's patch
    # radiosities: on the ceiling and the three walls, whose patch means are not limited by
    # the mesh at contacts, the lightmap's area mean is within 2 % of the area-weighted patch
    # mean (the bake's tolerance against the path tracer, crates/radiosity/tests/lightmap.rs;
    # measured 0.04-0.5 %). The same texel size in atlases of 80 texels a side gives several
    # atlases holding the same texels.
    s = radiosity.solve(radiosity.builtin("cornell"), solver="jacobi", patches=3000, tolerance=1e-4)
    m = s.bake_lightmap(texel_size=8.0, indirect=64)
    assert len(m["atlases"]) == 1
    atlas = m["atlases"][0]
    assert atlas.dtype == np.float32 and atlas.ndim == 3 and atlas.shape[2] == 3
    assert m["uv"].shape == (m["positions"].shape[0], 2)
    assert np.all((m["uv"] >= 0.0) & (m["uv"] <= 1.0))
    assert m["triangles"].shape[1] == 3 and m["triangle_surface"].shape == (m["triangles"].shape[0],)
    for k in (2, 6, 7, 8):  # ceiling, back, left and right walls
        sel = s.surfaces == k
        b = (s.radiosity[sel] * s.areas[sel, None]).sum(axis=0) / s.areas[sel].sum()
        lm = lightmap_quad_means(m, k)
        assert abs(lm.sum() / b.sum() - 1.0) < 0.02, (k, lm, b)
    several = s.bake_lightmap(texel_size=8.0, size=80, indirect=64)
    assert len(several["atlases"]) >= 2
    assert all(a.shape == (80, 80, 3) for a in several["atlases"])
    for k in range(s.surfaces.max() + 1):
        assert np.allclose(lightmap_quad_means(several, k), lightmap_quad_means(m, k), rtol=1e-5)
    denoised = s.bake_lightmap(texel_size=8.0, indirect=64, denoise=True)
    assert denoised["atlases"][0].shape == atlas.shape
    with pytest.raises(ValueError, match="texel size"):
        s.bake_lightmap(texel_size=-1.0)
