"""The process the kernels run in: Taichi start-up and its cache (startup), its
kernel frontend without the caret drawing (taichi_frontend), CPU worker threads bound
to cores (thread_binding), and where a step's wall time goes (phases). Layer 0: imports nothing of
tidem outside runtime/."""
