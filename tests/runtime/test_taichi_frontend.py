"""`tidem.runtime.taichi_frontend`: the kernel frontend's position messages without the caret rows,
still naming where a kernel fails to compile."""

from pathlib import Path

import pytest
import taichi as ti

from tidem.runtime import taichi_frontend


def test_the_light_position_message_is_in_place_after_start_up():
    from taichi.lang.ast.ast_transformer_utils import ASTTransformerContext

    assert taichi_frontend.install()
    assert ASTTransformerContext.get_pos_info is taichi_frontend.position


def test_a_kernel_that_fails_to_compile_is_named_by_file_line_and_code():
    x = ti.field(ti.f64, 4)

    @ti.kernel
    def broken():
        for i in x:
            x[i] = undefined_name_here  # noqa: F821

    with pytest.raises(ti.TaichiCompilationError) as err:
        broken()
    line = next(n for n, text in enumerate(Path(__file__).read_text().splitlines(), 1) if text.strip().startswith("x[i] = undefined"))
    message = str(err.value)
    assert f'File "{__file__}"' in message
    assert "x[i] = undefined_name_here" in message
    assert "in broken:" in message
    assert f", line {line}," in message
    assert "^^^" not in message  # no caret row: the light message


def test_a_factorys_kernels_read_their_source_once_and_keep_their_own_closures():
    """Kernels and Taichi functions made by a factory share a code object: the frontend reads its source
    once (`taichi_frontend._source`), and each kernel still takes its own closure's values."""
    from taichi.lang import kernel_impl

    assert kernel_impl._get_tree_and_ctx is taichi_frontend.tree_and_context

    def make(step):
        @ti.func
        def advanced(v):
            return v + step

        @ti.kernel
        def advance(x: ti.template()):
            for i in x:
                x[i] = advanced(x[i])

        return advance

    x = ti.field(ti.f64, 3)
    make(1.0)(x)
    make(2.0)(x)
    assert x.to_numpy().tolist() == [3.0, 3.0, 3.0]
    read = [key for key in taichi_frontend._sources if getattr(key, "co_name", "") in ("advanced", "advance")]
    assert len(read) == 2  # one per code object, not per kernel made
