"""kernels/field_copy.py: many fields to and from the host in one launch per element type, each
field's array exactly what its to_numpy() gives and what from_numpy() takes."""

import numpy as np
import taichi as ti

from tidem.kernels.field_copy import SERIAL_VALUES, FieldCopier


def _fields() -> dict:
    """Every layout a checkpoint holds: 0-d, 1-d, 2-d and 3-d index shapes; scalars, vectors and an
    n x m matrix; f64 and i32; two fields of one shape (one shared loop); loops in one thread and
    parallel ones."""
    return {
        "scalar0d": ti.field(ti.f64, shape=()),
        "vector0d": ti.Vector.field(3, ti.f64, shape=()),
        "T": ti.field(ti.f64, shape=7),
        "x": ti.Vector.field(3, ti.f64, shape=7),
        "ident": ti.field(ti.i32, shape=7),
        "rows": ti.field(ti.i32, shape=(7, 5)),
        "springs": ti.Vector.field(3, ti.f64, shape=(7, 5)),
        "cells": ti.field(ti.f64, shape=(4, 1, 6)),
        "faces": ti.field(ti.i32, shape=(5, 1, 6)),
        "matrix": ti.Matrix.field(2, 3, ti.f64, shape=(2, 4)),
        "column": ti.Matrix.field(19, 1, ti.f64, shape=(2,)),
        "big": ti.Vector.field(3, ti.f64, shape=SERIAL_VALUES // 3 + 1),  # over SERIAL_VALUES: a parallel loop
        "big_rows": ti.field(ti.i32, shape=(SERIAL_VALUES // 4 + 1, 4)),
    }


def _values(copier: FieldCopier, rng) -> dict:
    return {name: (rng.normal(size=copier.shape(name)) if s.field.dtype == ti.f64
                   else rng.integers(-1000, 1000, size=copier.shape(name)).astype(np.int32))
            for name, s in copier.slots.items()}


def test_read_gives_to_numpy_and_write_takes_from_numpy():
    rng = np.random.default_rng(7)
    fields = _fields()
    copier = FieldCopier(fields)
    truth = _values(copier, rng)
    for name, field in fields.items():
        assert copier.shape(name) == field.to_numpy().shape
        field.from_numpy(truth[name])
    got = copier.read()
    assert set(got) == set(fields)
    for name, field in fields.items():  # exact: a copy
        assert got[name].dtype == field.to_numpy().dtype, name
        np.testing.assert_array_equal(got[name], truth[name], err_msg=name)

    other = _values(copier, rng)
    copier.write(other)
    for name, field in fields.items():
        np.testing.assert_array_equal(field.to_numpy(), other[name], err_msg=name)
