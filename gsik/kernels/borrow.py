"""A numba structure's field read without reference counting: :func:`borrow`.

Reading a field of a ``numba.experimental.structref`` structure takes a reference to every array in it (NRT's atomic
increment, and a decrement when the value dies), and numba's reference-count pruning leaves most of those pairs in a
kernel that reads NamedTuples of arrays and calls other kernels. A controlled step read ~130 arrays that way
(:func:`gsik.kernels.step_inputs.control_step`), a frame ~50 more: ~400 atomic calls, each touching its array's
MemInfo, ~1 µs of a 19 µs step on bench_drag's studio drag. A kernel compiled without NRT (``_nrt=False``, which
allocates nothing) takes no references, but numba refuses a structure's field there (it reads the field through an
NRT call). :func:`borrow` reads it directly: the MemInfo's data pointer, then the field.

The structure must outlive the call (the caller holds it) and its fields must not be replaced during it (a
:class:`~gsik.kernels.step_inputs.StepInputs` is never written after it is made). In a kernel compiled with NRT,
:func:`borrow` takes the reference a field read takes, so it is always balanced.
"""

from __future__ import annotations

try:
    from llvmlite import ir
    from numba.core import cgutils, config, types
    from numba.extending import intrinsic
except ImportError:  # pragma: no cover - exercised only without numba
    intrinsic = None


def _data_pointer(context, builder, meminfo):
    """The data pointer of an NRT MemInfo, its fourth field (``refct, dtor, dtor_info, data, size``: numba's
    ``NRT_MemInfo``, what ``NRT_MemInfo_data_fast`` reads)."""
    word, pointer = context.get_value_type(types.intp), ir.IntType(8).as_pointer()
    layout = ir.LiteralStructType([word, pointer, pointer, pointer, word])
    return builder.load(cgutils.gep(builder, builder.bitcast(meminfo, layout.as_pointer()), 0, 3))


if intrinsic is None or config.DISABLE_JIT:  # the kernels run as Python: a field is an attribute

    def borrow(struct, name):
        """``getattr(struct, name)``: what the compiled :func:`borrow` reads, for kernels run as Python."""
        return getattr(struct, name)

else:

    @intrinsic
    def borrow(typingctx, struct, name):
        """``struct.<name>`` (``name`` a string literal) without taking a reference where the kernel is compiled
        without NRT; with NRT, the field read's own reference."""
        if not isinstance(struct, types.StructRef) or not isinstance(name, types.StringLiteral):
            return None
        field = name.literal_value
        if field not in struct.field_dict:
            return None
        field_type = struct.field_dict[field]

        def codegen(context, builder, signature, args):
            ref = cgutils.create_struct_proxy(struct)(context, builder, value=args[0])
            data_type = struct.get_data_type()
            data = builder.bitcast(_data_pointer(context, builder, ref.meminfo),
                                   context.get_value_type(data_type).as_pointer())
            value = getattr(cgutils.create_struct_proxy(data_type)(context, builder, ref=data), field)
            if context.enable_nrt:
                context.nrt.incref(builder, field_type, value)
            return value

        return field_type(struct, name), codegen
