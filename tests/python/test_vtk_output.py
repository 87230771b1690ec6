"""What `talus run` writes for ParaView, read back with VTK's own readers (Debian: python3-vtk9):
binary particle and machine snapshots in one .pvd collection, and the type-G terrain's surface.
The machine's bucket must be where the run's logged bucket tip says it is at each snapshot."""
import os
import subprocess
import xml.etree.ElementTree as ET

import numpy as np
import pytest

vtk = pytest.importorskip("vtk", reason="VTK's Python module is not installed (apt-get install python3-vtk9)")
from vtk.util.numpy_support import vtk_to_numpy  # noqa: E402

TALUS = os.path.join(os.environ.get("TALUS_BUILD_DIR", "build"), "talus")


def read(path, reader):
    r = reader()
    r.SetFileName(str(path))
    r.Update()
    return r.GetOutput()


def run(tmp_path, *args):
    out = tmp_path / "run"
    subprocess.run([TALUS, "run", "--quiet", "--out", str(out), *args], check=True)
    return out


def test_particle_and_machine_snapshots_read_back_in_one_collection(tmp_path):
    out = run(tmp_path, "--scenario", "hd27", "--fidelity", "D400", "--snapshot-interval", "2")
    summary = __import__("json").loads((out / "summary.json").read_text())
    log = np.genfromtxt(out / "timeseries.csv", delimiter=",", names=True)
    datasets = ET.parse(out / "particles.pvd").getroot().findall("./Collection/DataSet")
    times = sorted({float(d.get("timestep")) for d in datasets})
    assert times == [0.0, 2.0, 4.0, 6.0, 8.0]
    for d in datasets:
        assert "appended" in (out / d.get("file")).read_text(errors="ignore")[:3000]
        data = read(out / d.get("file"), vtk.vtkXMLPolyDataReader)
        t = float(d.get("timestep"))
        if d.get("part") == "0":
            # every particle, with radius and velocity arrays of the level's sizes
            assert data.GetNumberOfPoints() == summary["particles"] == data.GetNumberOfVerts()
            radius = vtk_to_numpy(data.GetPointData().GetArray("radius"))
            assert 0.1 < radius.mean() < 0.3
            assert vtk_to_numpy(data.GetPointData().GetArray("velocity")).shape == (summary["particles"], 3)
        else:
            # the machine: the bucket's triangles (part 0) near the logged tip, bodies, cylinders
            part = vtk_to_numpy(data.GetCellData().GetArray("part"))
            assert set(np.unique(part)) == {0, 1, 2} and np.count_nonzero(part == 2) == 3
            ids = vtk.vtkIdList()
            bucket_points = set()
            for c in np.flatnonzero(part == 0):
                data.GetCellPoints(int(c), ids)
                bucket_points.update(ids.GetId(k) for k in range(ids.GetNumberOfIds()))
            points = vtk_to_numpy(data.GetPoints().GetData())[sorted(bucket_points)]
            row = np.argmin(np.abs(log["t"] - t))
            tip = np.array([log["bucket_tip_x"][row], log["bucket_tip_z"][row]])
            nearest = np.min(np.hypot(points[:, 0] - tip[0], points[:, 2] - tip[1]))
            assert nearest < 0.05, f"t = {t}: the bucket mesh is {nearest:.3f} m from the logged tip"


def test_the_type_g_terrain_surface_reads_back(tmp_path):
    out = run(tmp_path, "--scenario", "hd27", "--fidelity", "G400", "--snapshot-interval", "0")
    grid = read(out / "terrain.vts", vtk.vtkXMLStructuredGridReader)
    nx, ny, nz = grid.GetDimensions()
    assert nx > 10 and ny > 3 and nz == 1
    height = vtk_to_numpy(grid.GetPointData().GetArray("height"))
    z = vtk_to_numpy(grid.GetPoints().GetData())[:, 2]
    assert np.array_equal(height, z)
    assert 1.5 < height.max() < 2.5  # the default pile stands 2 m high
    mass = vtk_to_numpy(grid.GetPointData().GetArray("mass"))
    assert mass.sum() > 0.0
