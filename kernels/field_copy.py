"""Many Taichi fields to and from host arrays in one kernel launch per element type.

`Field.to_numpy()` and `from_numpy()` compile (or load from the offline cache and JIT) a kernel
for every field, about 45 ms each on 2 cores: a checkpoint of fluidized_tube's 95 fields took
1.6-4.7 s the first time in a process (as Taichi's cache held them), most of a short run's output
time, and each call is a parallel launch (about 0.14 ms for a field of five values). Here the fields
of one element type (f64, i32, ...) are copied into one flat host array by a single kernel, each
field's values at an offset in numpy's C order of `to_numpy()` (index, then vector component or
matrix row and column), so that `read()` gives each field the array `to_numpy()` would, bit for bit.
Fields of the same shape share one loop (a loop is most of a kernel's compile time): 0.6-1.2 s for
the 95; a loop of at most SERIAL_VALUES values runs in the calling thread, without the thread pool's
round trip (`benchmarks/README.md`).
"""

import math
from dataclasses import dataclass

import numpy as np
import taichi as ti
from taichi.lang.field import Field
from taichi.lang.matrix import MatrixField
from taichi.lang.util import to_numpy_type

from .ordered import in_order


@dataclass(frozen=True)
class Slot:
    """Where a field's values lie in its element type's host array."""
    field: Field
    shape: tuple[int, ...]  # the field's index shape
    components: tuple[int, ...]  # () scalar, (n,) vector, (n, m) matrix
    offset: int

    @property
    def array_shape(self) -> tuple[int, ...]:
        return self.shape + self.components

    @property
    def size(self) -> int:
        return math.prod(self.array_shape)


# a loop copying at most this many values runs in the calling thread on the CPU: a time-series sample's
# particle arrays of fluidized_tube (52 000 values) in 0.07 ms, against 0.11 ms in a parallel loop; on a
# GPU, where one thread is thousands of times slower than the device, only the small groups
SERIAL_VALUES = 65536
SERIAL_VALUES_GPU = 4096


def _components(field: Field) -> tuple[int, ...]:
    if not isinstance(field, MatrixField):
        return ()
    return (field.n,) if field.m == 1 else (field.n, field.m)  # as to_numpy() has them


def _make_copy(slots: list[Slot], to_host: bool):
    """copy(buf): every slot's field into (to_host) or from its place in the flat array buf."""
    shapes = list(dict.fromkeys(s.shape for s in slots))
    groups = [(shape, [s for s in slots if s.shape == shape]) for shape in shapes]
    # a small group in one thread: a parallel loop waits about 50-100 us for the thread pool here
    limit = SERIAL_VALUES if in_order() else SERIAL_VALUES_GPU
    serial = [sum(s.size for s in members) <= limit for _shape, members in groups]

    @ti.func
    def copy_slot(buf: ti.template(), s: ti.template(), I: ti.template(), lin):
        """One index I (lin: its place in C order) of slot s's field."""
        at = s.offset + lin * ti.static(math.prod(s.components))
        if ti.static(len(s.components) == 0):
            if ti.static(to_host):
                buf[at] = s.field[I]
            else:
                s.field[I] = buf[at]
        elif ti.static(s.field.ndim == 1):  # a vector
            for c in ti.static(range(s.field.n)):
                if ti.static(to_host):
                    buf[at + c] = s.field[I][c]
                else:
                    s.field[I][c] = buf[at + c]
        else:  # a matrix (n x 1 ones as vectors in the array, as to_numpy() has them)
            for a, b in ti.static(ti.ndrange(s.field.n, s.field.m)):
                if ti.static(to_host):
                    buf[at + a * s.field.m + b] = s.field[I][a, b]
                else:
                    s.field[I][a, b] = buf[at + a * s.field.m + b]

    @ti.kernel
    def copy(buf: ti.types.ndarray()):
        for g in ti.static(range(len(groups))):
            shape, members = ti.static(groups[g])
            if ti.static(len(shape) == 0):
                for s in ti.static(members):
                    copy_slot(buf, s, None, 0)
            else:
                if ti.static(serial[g]):
                    ti.loop_config(serialize=True)
                for I in ti.grouped(ti.ndrange(*shape)):
                    lin = 0
                    for d in ti.static(range(len(shape))):
                        lin = lin * shape[d] + I[d]
                    for s in ti.static(members):
                        copy_slot(buf, s, I, lin)

    return copy


class FieldCopier:
    """read() -> {name: array as field.to_numpy() gives it}; write({name: array}) puts them back.
    The kernels are compiled at the first call of each."""

    def __init__(self, fields: dict[str, Field]):
        self.slots: dict[str, Slot] = {}
        self._types: dict = {}  # element type -> (numpy dtype, length, [names])
        for name, field in fields.items():
            np_type = to_numpy_type(field.dtype)
            kind = self._types.setdefault(field.dtype, [np_type, 0, []])
            slot = Slot(field, tuple(field.shape), _components(field), kind[1])
            self.slots[name] = slot
            kind[1] += slot.size
            kind[2].append(name)
        self._kernels: dict[tuple, object] = {}

    def shape(self, name: str) -> tuple[int, ...]:
        """The array shape of field `name` (as its to_numpy() has it)."""
        return self.slots[name].array_shape

    def _kernel(self, dtype, to_host: bool):
        key = (dtype, to_host)
        if key not in self._kernels:
            self._kernels[key] = _make_copy([self.slots[n] for n in self._types[dtype][2]], to_host)
        return self._kernels[key]

    def read(self) -> dict[str, np.ndarray]:
        out = {}
        for dtype, (np_type, length, names) in self._types.items():
            buf = np.empty(length, np_type)
            self._kernel(dtype, True)(buf)
            for name in names:
                s = self.slots[name]
                out[name] = buf[s.offset:s.offset + s.size].reshape(s.array_shape)
        return out

    def write(self, arrays: dict[str, np.ndarray]) -> None:
        """Every field from `arrays` (each of the field's array shape; all fields given)."""
        for dtype, (np_type, length, names) in self._types.items():
            buf = np.empty(length, np_type)
            for name in names:
                s = self.slots[name]
                buf[s.offset:s.offset + s.size] = np.asarray(arrays[name], np_type).reshape(-1)
            self._kernel(dtype, False)(buf)


def write_fields(values: dict[str, tuple[Field, object]]) -> None:
    """{name: (field, values)}: each field its array, or one number for all its values, in one launch per
    element type (Taichi's from_numpy and fill compile a kernel for every field)."""
    copier = FieldCopier({name: field for name, (field, _) in values.items()})
    copier.write({name: np.broadcast_to(value, copier.shape(name)) for name, (_, value) in values.items()})
