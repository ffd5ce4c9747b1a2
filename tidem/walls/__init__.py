"""What grains touch besides each other, set-up side (plain numpy): the box sides, plane walls and
tubes (surfaces), and triangle-mesh walls read from CAD files (mesh_load, mesh_geometry,
mesh_walls) and binned for the contact kernels (mesh_bins). Layer 1: may import layer 0
(scene, io, analytic, runtime)."""
