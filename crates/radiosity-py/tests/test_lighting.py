"""Lighting from Python: photometric files as arrays, and illuminance at points against the
inverse-square cosine law."""

import math

import numpy as np
import radiosity


def _isotropic(i0):
    gammas = " ".join(str(5 * k) for k in range(37))
    cd = " ".join([str(i0)] * 37)
    return f"IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 37 1 1 2 0 0 0\n1 1 0\n{gammas}\n0\n{cd}\n"


ROOM = (
    "mtllib room.mtl\nv 0 0 0\nv 6 0 0\nv 6 4 0\nv 0 4 0\nv 0 0 3\nv 6 0 3\nv 6 4 3\nv 0 4 3\n"
    "usemtl black\nf 1 2 3 4\nf 5 8 7 6\nf 1 5 6 2\nf 2 6 7 3\nf 3 7 8 4\nf 4 8 5 1\n"
)


def test_read_photometry_gives_the_table_and_its_flux(tmp_path):
    (tmp_path / "iso.ies").write_text(_isotropic(250.0))
    p = radiosity.read_photometry(tmp_path / "iso.ies")
    assert p["candela"].shape == (len(p["c_angles"]), 37)
    assert np.all(p["candela"] == 250.0)
    assert p["lumens"] is None  # absolute photometry
    assert abs(p["flux"] - 4 * math.pi * 250.0) < 1e-9 * p["flux"]


def test_lighting_matches_the_inverse_square_law_with_black_walls(tmp_path):
    (tmp_path / "room.obj").write_text(ROOM)
    (tmp_path / "room.mtl").write_text("newmtl black\nKd 0 0 0\n")
    (tmp_path / "a.ies").write_text(_isotropic(800.0))
    (tmp_path / "s.csv").write_text(
        "name,file,x,y,z,aim_x,aim_y,aim_z,c0_x,c0_y,c0_z,multiplier,group\n"
        "A,a.ies,1.5,2,2.5,,,,,,,1,north\n"
        "B,a.ies,4.5,2,2.5,,,,,,,0.25,south\n"
    )
    pts = np.array(
        [[0.5 + i, 0.5 + j, 0.8, 0.0, 0.0, 1.0] for i in range(6) for j in range(4)]
    )
    scene = radiosity.load(str(tmp_path / "room.obj"))
    r = radiosity.lighting(scene, tmp_path / "s.csv", points=pts, patches=300)
    assert r["groups"] == ["north", "south"]
    assert r["by_group"].shape == (24, 2)
    h = 2.5 - 0.8
    for k, p in enumerate(pts):
        want = 0.0
        for lx, m in [(1.5, 1.0), (4.5, 0.25)]:
            d2 = (p[0] - lx) ** 2 + (p[1] - 2.0) ** 2 + h * h
            want += m * 800.0 * h / math.sqrt(d2) / d2
        assert abs(r["illuminance"][k] - want) < 1e-9 * want
    np.testing.assert_allclose(r["by_group"].sum(axis=1), r["illuminance"], rtol=1e-12)
