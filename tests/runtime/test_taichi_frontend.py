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
