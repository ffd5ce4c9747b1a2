"""Taichi's kernel frontend without its per-node caret drawing, reading each function's source once.

Before Taichi compiles a kernel, its Python frontend walks the kernel's syntax tree and, for every
node, renders the node's source position as a message: the file and line, then the line's code
and a row of carets under the node, each wrapped to 80 columns by `textwrap`
(`ASTTransformerContext.get_pos_info`, Taichi 1.7). The message is kept only in case that node
fails to compile. tidem's kernels hold about 150 000 nodes per scene (static loops unrolled), so
the wrapping alone took a fifth of a cold kernel build and most of a cached one. `position` gives
the file, line, function and the line's code, without the caret row: a compile error still says
where it is.

The frontend also reads a function's source from its file (`inspect`: the file's lines, then the
function's block by tokenizing), re-fills each line and dedents them every time it parses a kernel
or inlines a Taichi function: about a thousand times per scene, since every call site of a
`ti.func` is inlined anew, and for every scene again, since kernels are made by factories.
`tree_and_context` reads that text once per code object (`_source`) and parses it as before; the
text of a function cannot change while its code object lives, so the tree is the one Taichi's own
`_get_tree_and_ctx` builds. Measured on the test suite's gas bed (a cold build and 20 steps):
that reading was 1.8 s of 15-17 s.

Both replacements are debug and I/O paths only, so no computed value changes; each is installed only
where Taichi has the function it replaces.
"""

from __future__ import annotations

import ast
import textwrap


def position(self, node) -> str:
    """Where `node` is: `File "...", line N, in kernel:` and that line's code (the context's source)."""
    return (f'File "{self.file}", line {node.lineno + self.lineno_offset}, in {self.func.func.__name__}:\n'
            f"{self.src[node.lineno - 1]}\n")


_sources: dict = {}  # code object -> (file, lines as the frontend has them, first line, dedented text)


def _source(func) -> tuple:
    """A kernel's or Taichi function's source as Taichi's frontend reads it (its file, its lines with tabs
    expanded, the first line's number, the dedented text), read once per code object."""
    from taichi.lang._wrap_inspect import getsourcefile, getsourcelines

    key = getattr(func, "__code__", func)
    found = _sources.get(key)
    if found is None:
        src, start = getsourcelines(func)
        lines = [textwrap.fill(line, tabsize=4, width=9999) for line in src]
        found = _sources[key] = (getsourcefile(func), lines, start, textwrap.dedent("\n".join(lines)))
    return found


def tree_and_context(self, excluded_parameters=(), is_kernel=True, arg_features=None, args=None, ast_builder=None,
                     is_real_function=False):
    """Taichi's `kernel_impl._get_tree_and_ctx` (1.7) over the source `_source` keeps: a fresh syntax tree of
    the function without its decorators, and the transformer's context with the function's globals and the
    template arguments of a kernel or real function."""
    from taichi.lang import kernel_impl
    from taichi.lang.ast.ast_transformer_utils import ASTTransformerContext

    file, src, start_lineno, text = _source(self.func)
    tree = ast.parse(text)
    tree.body[0].decorator_list = []
    global_vars = kernel_impl._get_global_vars(self.func)
    if is_kernel or is_real_function:
        for i in self.template_slot_locations:
            global_vars[self.arguments[i].name] = args[i]
    return tree, ASTTransformerContext(
        excluded_parameters=excluded_parameters, is_kernel=is_kernel, func=self, arg_features=arg_features,
        global_vars=global_vars, argument_data=args, src=src, start_lineno=start_lineno, file=file,
        ast_builder=ast_builder, is_real_function=is_real_function)


def install() -> bool:
    """Put `position` in place of Taichi's `get_pos_info` and `tree_and_context` in place of its
    `_get_tree_and_ctx`; True when both are in place."""
    try:
        from taichi.lang import kernel_impl
        from taichi.lang.ast.ast_transformer_utils import ASTTransformerContext
    except ImportError:  # another Taichi: keep its own
        return False
    placed = True
    if callable(getattr(ASTTransformerContext, "get_pos_info", None)):
        ASTTransformerContext.get_pos_info = position
    else:
        placed = False
    if callable(getattr(kernel_impl, "_get_tree_and_ctx", None)) and callable(getattr(kernel_impl, "_get_global_vars", None)):
        kernel_impl._get_tree_and_ctx = tree_and_context
    else:
        placed = False
    return placed
