"""Triangle-mesh walls (`model.meshes`, `tidem.walls.mesh_walls.MeshWall`) in a run folder, for
ParaView and for the frames.

    meshes/mesh<k>.vtp          mesh k at t = 0, written once when the run folder is set up;
                                the frames draw it, moved to each frame's time
    meshes/mesh<k>_<NNNNN>.vtp  a moving mesh, or one whose temperature follows a schedule, at the
                                time of snapshot NNNNN (with a TimeValue)
    meshes.pvd                  the time collection beside snapshots.pvd: at each snapshot time
                                one part per mesh (part k), a static mesh's one file listed at
                                every time, so ParaView shows the meshes moving with the bed

Each file is a PolyData of triangles; a mesh with a fixed temperature carries a point array
`temperature` [K], the name the particles' array has, so one colour map spans both.
run.json's `render_geometry.meshes` (`mesh_geometry`) names each mesh's t = 0 file and its
rigid motion with any schedules of it: the renderer needs nothing else, not the scene file or the
CAD file.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tidem.io.vtp import write_pvd, write_vtp_triangles

MESH_DIR = "meshes"
PVD_NAME = "meshes.pvd"


def mesh_file(k: int, snapshot: int | None = None) -> str:
    """File of mesh k relative to the run folder: at t = 0, or at snapshot number `snapshot`."""
    return f"{MESH_DIR}/mesh{k}.vtp" if snapshot is None else f"{MESH_DIR}/mesh{k}_{snapshot:05d}.vtp"


def mesh_geometry(meshes) -> list[dict]:
    """run.json's `render_geometry.meshes`: each mesh's t = 0 file, temperature and motion."""
    return [{"name": m.name, "file": mesh_file(k), "T": m.temperature, "center": [float(c) for c in m.center],
             "axis": [float(a) for a in m.axis], "speed": float(m.speed),
             "velocity": [float(v) for v in m.velocity], "source": str(m.source),
             "schedules": {key: s.model_dump() for key, s in m.schedules.items()}}
            for k, m in enumerate(meshes)]


def _changes(mesh) -> bool:
    """A mesh written at every snapshot: it moves, or its temperature follows a schedule."""
    return mesh.moving or "temperature" in mesh.schedules


def _arrays(mesh, t: float = 0.0) -> dict[str, np.ndarray]:
    if mesh.temperature is None:
        return {}
    return {"temperature": np.full(len(mesh.vertices), float(mesh.temperature_at(t)))}


class MeshOutput:
    """The meshes of one run folder. `entries` is the run's snapshot list ((time, file) rows of
    snapshots.pvd), shared with `tidem.runner.output.Output`: row i is snapshot number i."""

    def __init__(self, run_dir: Path, meshes: list, entries: list[tuple[float, str]]):
        """Write each mesh at t = 0; on a resumed run (`entries` not empty) keep the moving meshes'
        files of the kept snapshots and drop later ones."""
        self.dir = Path(run_dir)
        self.meshes = list(meshes)
        self.entries = entries
        folder = self.dir / MESH_DIR
        if not self.meshes:
            (self.dir / PVD_NAME).unlink(missing_ok=True)
            return
        folder.mkdir(parents=True, exist_ok=True)
        kept = {mesh_file(k, i) for k, m in enumerate(self.meshes) if _changes(m) for i in range(len(entries))}
        kept |= {mesh_file(k) for k in range(len(self.meshes))}
        for old in [*folder.glob("*.vtp"), *folder.glob("*.tmp")]:
            if f"{MESH_DIR}/{old.name}" not in kept:
                old.unlink()
        for k, m in enumerate(self.meshes):
            write_vtp_triangles(self.dir / mesh_file(k), m.vertices, m.triangles, _arrays(m))
        self._write_pvd()

    def snapshot(self) -> None:
        """After the run has listed a snapshot in `entries`: write each moving mesh (or scheduled
        temperature) at its time and list the meshes at that time in meshes.pvd."""
        if not self.meshes:
            return
        index = len(self.entries) - 1
        t = self.entries[index][0]
        for k, m in enumerate(self.meshes):
            if _changes(m):
                write_vtp_triangles(self.dir / mesh_file(k, index), m.points_at(t), m.triangles, _arrays(m, t), time=t)
        self._write_pvd()

    def pvd_rows(self) -> list[tuple[float, int, str]]:
        """(time, part, file) of meshes.pvd: every mesh at every snapshot time."""
        return [(t, k, mesh_file(k, i if _changes(m) else None))
                for i, (t, _name) in enumerate(self.entries) for k, m in enumerate(self.meshes)]

    def _write_pvd(self) -> None:
        rows = self.pvd_rows()
        if rows:
            write_pvd(self.dir / PVD_NAME, [(t, f) for t, _k, f in rows], parts=[k for _t, k, _f in rows])
        else:
            (self.dir / PVD_NAME).unlink(missing_ok=True)
