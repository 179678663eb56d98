"""A weighted sum of rows with its sums held in vector registers: :func:`combine_rows`.

The range-space step (:mod:`gsik.kernels.range_space`) builds ``C H^-1``, ``H^-1 b`` and its steps as weighted sums
of rows, ``out += w[i] X[i]`` row after row. Written as numba loops, each row is a vectorised sweep that loads and
stores ``out``: the next row waits on that store, ~7 ns a row of 30 whatever its work. Holding ``out`` in registers
across the rows needs numba's SLP vectoriser, which it leaves off by default (it miscompiled; numba PR #8852) and
only switches on for a whole process. :func:`combine_rows` emits that loop directly in LLVM IR: 32 columns at a time
in four 8-wide registers (masked at the end of a row), one fused multiply-add per row and register. Per column the
sums are the loop's: ``out + w[0] X[0] + w[1] X[1] ...`` in order, each multiply-add fused as ``fastmath``'s
``contract`` fuses it (``llvm.fmuladd``), so the results are those of the loop it replaces. ``C H^-1`` of bench_drag's
studio drag (18 rows of 30 by 30): 0.63 µs against the loop's 1.34.

Without numba (or with ``NUMBA_DISABLE_JIT``) :func:`combine_rows` is that loop in Python.
"""

from __future__ import annotations

from gsik._jit import njit

#: Lanes per register (doubles in 512 bits; LLVM splits them where registers are narrower) and registers per block.
LANES, REGISTERS = 8, 4


def combine_rows(w, X, out):
    """``out[:m] += w[:k] @ X[:k, :m]`` (``w`` (k,), ``X`` (>= k, >= m) C-contiguous, ``out`` (m,) contiguous; ``k =
    len(w)``, ``m = len(out)``), row by row in order, a row of weight 0 skipped (adds nothing, not even a NaN)."""
    m = out.shape[0]
    for i in range(w.shape[0]):
        if w[i] != 0.0:
            for c in range(m):
                out[c] += w[i] * X[i, c]


try:
    from llvmlite import ir
    from numba import types
    from numba.core import cgutils
    from numba.extending import intrinsic, overload
    from numba.np.arrayobj import make_array
except ImportError:  # pragma: no cover - exercised only without numba
    intrinsic = None

if intrinsic is not None:
    _F64 = ir.DoubleType()
    _I64, _I32 = ir.IntType(64), ir.IntType(32)
    _VEC, _MASK = ir.VectorType(_F64, LANES), ir.VectorType(ir.IntType(1), LANES)

    def _readable(w, X, out):
        """True if ``w``, ``X``, ``out`` are the float arrays (1-d, 2-d, 1-d) C-contiguous that the loop reads."""
        return all(isinstance(a, types.Array) and a.ndim == ndim and a.dtype == types.float64 and a.layout == "C"
                   for a, ndim in ((w, 1), (X, 2), (out, 1)))

    def _splat(builder, value, typ):
        """``value`` in every lane."""
        vector = ir.VectorType(typ, LANES)
        first = builder.insert_element(ir.Constant(vector, ir.Undefined), value, ir.Constant(_I32, 0))
        return builder.shuffle_vector(first, ir.Constant(vector, ir.Undefined),
                                      ir.Constant(ir.VectorType(_I32, LANES), [0] * LANES))

    def _functions(module):
        """LLVM's masked load and store and its fused-if-faster multiply-add, on 8 doubles."""
        ptr = ir.PointerType(_F64)
        declare = cgutils.get_or_insert_function
        return (declare(module, ir.FunctionType(_VEC, [ptr, _I32, _MASK, _VEC]), "llvm.masked.load.v8f64.p0"),
                declare(module, ir.FunctionType(ir.VoidType(), [_VEC, ptr, _I32, _MASK]),
                        "llvm.masked.store.v8f64.p0"),
                declare(module, ir.FunctionType(_VEC, [_VEC, _VEC, _VEC]), "llvm.fmuladd.v8f64"))

    def _block(builder, functions, start, m, w, X, out, accumulators):
        """Columns ``start : start + 32`` (those below ``m``): the sums loaded from ``out``, every row of nonzero
        weight multiplied into them, stored back."""
        load, store, fmuladd = functions
        ptr, align, zero = ir.PointerType(_F64), ir.Constant(_I32, 8), ir.Constant(_VEC, [0.0] * LANES)
        lanes = ir.Constant(ir.VectorType(_I64, LANES), list(range(LANES)))
        columns = [builder.add(start, ir.Constant(_I64, LANES * r)) for r in range(REGISTERS)]
        masks = [builder.icmp_unsigned("<", builder.add(_splat(builder, c, _I64), lanes), _splat(builder, m, _I64))
                 for c in columns]
        targets = [builder.gep(out.data, [c]) for c in columns]
        for r, acc in enumerate(accumulators):
            builder.store(builder.call(load, [targets[r], align, masks[r], zero]), acc)
        k = cgutils.unpack_tuple(builder, w.shape, 1)[0]
        row_bytes = cgutils.unpack_tuple(builder, X.strides, 2)[0]
        with cgutils.for_range(builder, k) as row:
            weight = builder.load(builder.gep(w.data, [row.index]))
            with builder.if_then(builder.fcmp_unordered("!=", weight, ir.Constant(_F64, 0.0))):
                weights = _splat(builder, weight, _F64)
                base = builder.inttoptr(builder.add(builder.ptrtoint(X.data, _I64), builder.mul(row.index, row_bytes)),
                                        ptr)
                for r, acc in enumerate(accumulators):
                    x = builder.call(load, [builder.gep(base, [columns[r]]), align, masks[r], zero])
                    builder.store(builder.call(fmuladd, [weights, x, builder.load(acc)]), acc)
        for r, acc in enumerate(accumulators):
            builder.call(store, [builder.load(acc), targets[r], align, masks[r]])

    @intrinsic
    def _combine_rows(typingctx, w, X, out):
        """:func:`combine_rows` in LLVM IR (the accumulators are stack slots that LLVM promotes to registers)."""
        if not _readable(w, X, out):
            return None  # numba's typing error: no compiled code, rather than wrong sums
        signature = types.void(w, X, out)

        def codegen(context, builder, sig, args):
            wa, xa, oa = (make_array(t)(context, builder, a) for t, a in zip(sig.args, args))
            functions = _functions(builder.module)
            accumulators = [cgutils.alloca_once(builder, _VEC) for _ in range(REGISTERS)]
            m = cgutils.unpack_tuple(builder, oa.shape, 1)[0]
            width = LANES * REGISTERS
            blocks = builder.udiv(builder.add(m, ir.Constant(_I64, width - 1)), ir.Constant(_I64, width))
            with cgutils.for_range(builder, blocks) as block:
                start = builder.mul(block.index, ir.Constant(_I64, width))
                _block(builder, functions, start, m, wa, xa, oa, accumulators)
            return context.get_dummy_value()

        return signature, codegen

    @overload(combine_rows, inline="always")
    def _combine_rows_overload(w, X, out):
        if _readable(w, X, out):
            return lambda w, X, out: _combine_rows(w, X, out)
        return None


@njit(cache=True, _nrt=False, inline="always")
def subtract_rows(lam, X, m, out):
    """``out -= lam[:m] @ X[:m]`` (``lam`` negated in place)."""
    for i in range(m):
        lam[i] = -lam[i]
    combine_rows(lam[:m], X[:m], out)
