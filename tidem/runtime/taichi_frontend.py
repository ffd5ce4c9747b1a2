"""Taichi's kernel frontend without its per-node caret drawing.

Before Taichi compiles a kernel, its Python frontend walks the kernel's syntax tree and, for every
node, renders the node's source position as a message: the file and line, then the line's code
and a row of carets under the node, each wrapped to 80 columns by `textwrap`
(`ASTTransformerContext.get_pos_info`, Taichi 1.7). The message is kept only in case that node
fails to compile. tidem's kernels hold about 150 000 nodes per scene (static loops unrolled), so
the wrapping alone took a fifth of a cold kernel build and most of a cached one.

`install` replaces that method with one that gives the file, line, function and the line's code,
without the caret row: a compile error still says where it is. The message is debug information
only, so no computed value changes; it is installed only where Taichi has the method it replaces.
"""

from __future__ import annotations


def position(self, node) -> str:
    """Where `node` is: `File "...", line N, in kernel:` and that line's code (the context's source)."""
    return (f'File "{self.file}", line {node.lineno + self.lineno_offset}, in {self.func.func.__name__}:\n'
            f"{self.src[node.lineno - 1]}\n")


def install() -> bool:
    """Put `position` in place of Taichi's `get_pos_info`; True when it is in place."""
    try:
        from taichi.lang.ast.ast_transformer_utils import ASTTransformerContext
    except ImportError:  # another Taichi: keep its own
        return False
    if not callable(getattr(ASTTransformerContext, "get_pos_info", None)):
        return False
    ASTTransformerContext.get_pos_info = position
    return True
