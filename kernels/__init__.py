"""Taichi kernels of tidem (installed as `tidem.kernels`).

Kernels never see the scene schema: `tidem.sim.solver` hands them a namespace of Taichi fields and
plain numbers, and builds only the kernels a scene needs.
"""
