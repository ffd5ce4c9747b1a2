"""The gas phase: its grid and boundaries (geometry, limits), mesh walls cut into it (mesh,
apertures, open_volume, grid_graph, mesh_convection), its Taichi fields (fields), O2 (species),
and GasPhase (phase), which runs the kernels of kernels/gas_*.py. Layer 2: may import walls/ and
layer 0."""
