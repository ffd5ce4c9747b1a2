"""Model, State and Solver: what a run holds fixed (model, features, memory), the Taichi fields
that change (state, state_fill), and the Solver that builds the kernels a scene needs and
advances them (solver, solver_reads, kernel_settings). Layer 5, beside render/, which it never
imports: may import every layer below."""
