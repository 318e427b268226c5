"""Compiled kernels called from other compiled code through function pointers, so that they
run their own machine code: the bits they give when Python calls them.

A compiled caller that calls a kernel by name has the kernel's optimised code (LLVM IR)
linked into its own module, where LLVM optimises it anew with the caller's and may inline
it. For a kernel compiled with fast-math flags (:data:`~railcontact.normal.bem.REASSOCIATE`:
sums may be reordered and vectorised, multiply-adds fused) the new machine code can sum
in another order, and the last bits of its results change (1 ulp, which an iteration
carries on). Called through a pointer whose value the caller learns only when it runs,
the kernel is neither inlined nor compiled again: it runs its own machine code, the code
a call from Python runs.

:func:`address` gives the address of a kernel's code for one signature (compiled when
needed; the calls from Python with those argument types run that very code), once per
process: the conversion costs about 30 us, which numba would pay at every call from
Python if the kernel itself were the argument of a compiled function. In compiled code
:func:`function_at` of a signature makes of such an address (an int64, e.g. an element
of an array of addresses given to the caller) a first-class function
(``numba.types.FunctionType``) that is called as the kernel, through the pointer.
Nothing in the caller's code depends on an address, so the caller is cached
(``cache=True``) as any kernel.
"""

from __future__ import annotations

from functools import cache

try:
    import numba
    from numba.core import cgutils, types
    from numba.experimental.function_type import _get_jit_address
    from numba.extending import intrinsic
except ImportError:  # pragma: no cover
    numba = None


def address(kernel, signature) -> int:
    """The address of ``kernel``'s compiled code (numba's calling convention) for
    ``signature`` (``return_type(*argument_types)``, the types of the calls from Python;
    compiled for it if not yet), as an int for :func:`function_at`."""
    addr = _get_jit_address(kernel, signature)
    if addr <= 0:  # pragma: no cover - a kernel numba did not compile
        raise RuntimeError(f"no compiled code of {kernel} for {signature}")
    return addr


@cache
def function_at(signature):
    """A compiled function ``f(addr)`` (numba intrinsic, for compiled code only) that makes
    the address ``addr`` (an integer, :func:`address`) of a kernel's code for
    ``signature`` a first-class function of that signature: calls of it go through the
    pointer (the kernel's own code; LLVM cannot inline it)."""
    fnty = types.FunctionType(signature)

    @intrinsic
    def at(typingctx, addr):  # pragma: no cover - compiled
        if not isinstance(addr, types.Integer):
            return None

        def codegen(context, builder, sig, args):
            fn = cgutils.create_struct_proxy(fnty)(context, builder)  # (zeroed)
            fn.jit_addr = builder.inttoptr(args[0], context.get_value_type(types.voidptr))
            return fn._getvalue()

        return fnty(addr), codegen

    return at
