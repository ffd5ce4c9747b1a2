"""A parallel loop that keeps every CPU worker of Taichi's thread pool busy for some milliseconds
(`tidem.runtime.thread_binding` tells the workers from Taichi's other threads by it)."""

import taichi as ti


@ti.kernel
def busy_loop(items: ti.i32) -> ti.f64:
    """Sum of sin over items x 64 arguments (returned, so that the loop is not optimised away)."""
    total = ti.cast(0.0, ti.f64)
    for i in range(items):
        v = ti.cast(0.0, ti.f64)
        for k in range(64):
            v += ti.sin(ti.cast(0.001 * i + k, ti.f64))
        total += v
    return total
