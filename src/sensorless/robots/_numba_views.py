"""C-contiguous views of C-contiguous arrays in numba kernels, without numba's reshape helper.

numba compiles ``flat.reshape(shape)`` to a call of a C helper that looks for
a copy-free layout, about 30 ns a call; a kernel step that views its flat
arrays seven times pays 0.2 µs for it. :func:`view` builds the view of a
C-contiguous array directly (same data, same owner, same writability),
after checking that the sizes agree as ``reshape`` does. Importing this
module requires numba.
"""

from __future__ import annotations

from typing import Any, cast

from numba.core import cgutils, types
from numba.core.imputils import impl_ret_borrowed
from numba.extending import intrinsic
from numba.np.arrayobj import make_array, populate_array

__all__ = ["view"]


@intrinsic
def _view(typingctx: Any, flat: Any, shape: Any) -> Any:
    """``flat.reshape(shape)`` for a C-contiguous ``flat``, in a compiled function.

    ``shape`` is a tuple of integers; the result is C-contiguous, shares
    ``flat``'s memory and is read-only when ``flat`` is. Raises ValueError
    (in the compiled code) when ``flat`` does not hold exactly the items of
    ``shape``.
    """
    kinds: list[Any] = list(cast(Any, shape)) if isinstance(shape, types.BaseTuple) else [None]
    if not (
        isinstance(flat, types.Array)
        and flat.layout == "C"
        and all(isinstance(kind, types.Integer) for kind in kinds)
    ):
        return None
    ndim = len(kinds)
    result = flat.copy(ndim=ndim, layout="C")

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        flat_value, shape_value = args
        source = make_array(flat)(context, builder, flat_value)
        items = cgutils.unpack_tuple(builder, shape_value, ndim)
        sizes = [context.cast(builder, v, t, types.intp) for v, t in zip(items, kinds, strict=True)]
        total = context.get_constant(types.intp, 1)
        for size in sizes:
            total = builder.mul(total, size)
        with builder.if_then(builder.icmp_signed("!=", total, source.nitems), likely=False):
            message = "view: the array's size differs from the product of the shape"
            context.call_conv.return_user_exc(builder, ValueError, (message,))
        strides = [source.itemsize] * ndim
        for axis in range(ndim - 2, -1, -1):
            strides[axis] = builder.mul(strides[axis + 1], sizes[axis + 1])
        target = make_array(result)(context, builder)
        populate_array(
            target,
            data=source.data,
            shape=sizes,
            strides=strides,
            itemsize=source.itemsize,
            meminfo=source.meminfo,
            parent=source.parent,
        )
        return impl_ret_borrowed(context, builder, result, target._getvalue())

    return result(flat, shape), codegen


view: Any = _view
