"""Vector kernels of the stepper's hot products, written as numba intrinsics (LLVM IR).

numba has no vector types, and LLVM's vectorisers leave the stepper's small products scalar:
the nine sums of `kernels._mv9` stay nine scalar multiply-add chains, and an array accumulator is
reloaded at every column because numba cannot promise LLVM that arrays do not alias
(docs/performance.md). These intrinsics state the vector form directly: eight of the nine rows
of q'' in one vector of eight doubles, and the four corners' deflections and rates in one. LLVM
lowers a vector of eight to one AVX-512 register, two AVX2 registers or four NEON registers, and
``llvm.fma`` to the machine's fused multiply-add, as the scalar code's contracted products were.

Every array argument must be C-contiguous (checked when the calling kernel is compiled); row
lengths are read from the arrays' strides.
"""

from __future__ import annotations

from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.core.errors import TypingError
from numba.extending import intrinsic

_I32 = ir.IntType(32)
_I64 = ir.IntType(64)
_F64 = ir.DoubleType()
_V8 = ir.VectorType(_F64, 8)
_V4 = ir.VectorType(_F64, 4)


def _check_contiguous(name, *arrays):
    for a in arrays:
        if not isinstance(a, types.Array) or a.layout != "C" or a.dtype != types.float64:
            raise TypingError(f"{name}: needs C-contiguous float64 arrays, got {a}")


def _fma8(builder):
    return cgutils.get_or_insert_function(builder.module, ir.FunctionType(_V8, [_V8] * 3), "llvm.fma.v8f64")


def _fma1(builder):
    return cgutils.get_or_insert_function(builder.module, ir.FunctionType(_F64, [_F64] * 3), "llvm.fma.f64")


def _load8(builder, ptr):
    return builder.load(builder.bitcast(ptr, _V8.as_pointer()), align=8)


def _splat8(builder, x):
    v = builder.insert_element(ir.Constant(_V8, ir.Undefined), x, ir.Constant(_I32, 0))
    return builder.shuffle_vector(v, ir.Constant(_V8, ir.Undefined), ir.Constant(ir.VectorType(_I32, 8), [0] * 8))


def _row_length(builder, arr):
    """Elements per row of a C-contiguous 2-D float64 array."""
    return builder.sdiv(cgutils.unpack_tuple(builder, arr.strides, 2)[0], ir.Constant(_I64, 8))


@intrinsic
def mv9_simd(typingctx, AT, x, xf, n_cols, r, roff, out, ooff):
    """out[ooff + i] = r[roff + i] + sum_j AT[j, i] v[j] for the nine rows i, v[j] = x[j] for
    j < 18 (q, q') and xf[j] beyond (the corner forces); AT is (n_cols, 9).

    Rows 0-7 form one vector of eight, row 8 a scalar. The columns are summed in three
    independent chains, q (0-8), q' (9-17) and the forces from r (18-), added at the end: one
    chain of 22 multiply-adds made the product wait on its own latency."""
    _check_contiguous("mv9_simd", AT, x, xf, r, out)
    sig = types.void(AT, x, xf, n_cols, r, roff, out, ooff)

    def codegen(context, builder, signature, args):
        at = context.make_array(signature.args[0])(context, builder, args[0])
        xa = context.make_array(signature.args[1])(context, builder, args[1])
        xfa = context.make_array(signature.args[2])(context, builder, args[2])
        ra = context.make_array(signature.args[4])(context, builder, args[4])
        oa = context.make_array(signature.args[6])(context, builder, args[6])
        nc = context.cast(builder, args[3], signature.args[3], types.int64)
        ro = context.cast(builder, args[5], signature.args[5], types.int64)
        oo = context.cast(builder, args[7], signature.args[7], types.int64)
        width = _row_length(builder, at)
        fma8, fma1 = _fma8(builder), _fma1(builder)
        one = ir.Constant(_I64, 1)
        eight = ir.Constant(_I64, 8)
        rp = builder.gep(ra.data, [ro])
        zero8, zero1 = ir.Constant(_V8, [0.0] * 8), ir.Constant(_F64, 0.0)
        sums = []
        for src, lo, hi, init8, init1 in (
            (xa, ir.Constant(_I64, 0), ir.Constant(_I64, 9), zero8, zero1),
            (xa, ir.Constant(_I64, 9), ir.Constant(_I64, 18), zero8, zero1),
            (xfa, ir.Constant(_I64, 18), nc, _load8(builder, rp), builder.load(builder.gep(rp, [eight]))),
        ):
            acc8 = cgutils.alloca_once_value(builder, init8)
            acc1 = cgutils.alloca_once_value(builder, init1)
            with cgutils.for_range_slice(builder, lo, hi, one, inc=True) as (j, _):
                xj = builder.load(builder.gep(src.data, [j]))
                row = builder.gep(at.data, [builder.mul(j, width)])
                col8 = _load8(builder, row)
                builder.store(builder.call(fma8, [col8, _splat8(builder, xj), builder.load(acc8)]), acc8)
                last = builder.load(builder.gep(row, [eight]))
                builder.store(builder.call(fma1, [last, xj, builder.load(acc1)]), acc1)
            sums.append((builder.load(acc8), builder.load(acc1)))
        (q8, q1), (v8, v1), (f8, f1) = sums
        op = builder.gep(oa.data, [oo])
        builder.store(builder.fadd(f8, builder.fadd(q8, v8)), builder.bitcast(op, _V8.as_pointer()), align=8)
        builder.store(builder.fadd(f1, builder.fadd(q1, v1)), builder.gep(op, [eight]))
        return context.get_dummy_value()

    return sig, codegen


@intrinsic
def corner_pairs(typingctx, TT, s, cx, cv):
    """cx[c] = sum_j TT[j, c] s[j] and cv[c] = sum_j TT[j, c] s[9 + j] (c < 4, j < 9): the
    secondary deflections and their rates at the four corners, as one vector of eight."""
    _check_contiguous("corner_pairs", TT, s, cx, cv)
    sig = types.void(TT, s, cx, cv)

    def codegen(context, builder, signature, args):
        tt = context.make_array(signature.args[0])(context, builder, args[0])
        sa = context.make_array(signature.args[1])(context, builder, args[1])
        xa = context.make_array(signature.args[2])(context, builder, args[2])
        va = context.make_array(signature.args[3])(context, builder, args[3])
        fma8 = _fma8(builder)
        width = _row_length(builder, tt)
        acc = ir.Constant(_V8, [0.0] * 8)
        twice = ir.Constant(ir.VectorType(_I32, 8), [0, 1, 2, 3, 0, 1, 2, 3])
        for j in range(9):
            row_ptr = builder.gep(tt.data, [builder.mul(ir.Constant(_I64, j), width)])
            row = builder.load(builder.bitcast(row_ptr, _V4.as_pointer()), align=8)
            both = builder.shuffle_vector(row, ir.Constant(_V4, ir.Undefined), twice)
            q = builder.load(builder.gep(sa.data, [ir.Constant(_I64, j)]))
            qd = builder.load(builder.gep(sa.data, [ir.Constant(_I64, 9 + j)]))
            sv = ir.Constant(_V8, ir.Undefined)
            for k in range(8):
                sv = builder.insert_element(sv, q if k < 4 else qd, ir.Constant(_I32, k))
            acc = builder.call(fma8, [both, sv, acc])
        for dest, lanes in ((xa, [0, 1, 2, 3]), (va, [4, 5, 6, 7])):
            pick = ir.Constant(ir.VectorType(_I32, 4), lanes)
            half = builder.shuffle_vector(acc, ir.Constant(_V8, ir.Undefined), pick)
            builder.store(half, builder.bitcast(dest.data, _V4.as_pointer()), align=8)
        return context.get_dummy_value()

    return sig, codegen


@intrinsic
def forcing_rows(typingctx, ftab, a, h00, h10, h01, h11, d00, d10, d11, out, ooff):
    """out[ooff + i] (i < 9) = h00 P_a + h10 Q_a + h01 P_b + h11 Q_b + d00 (R_a - R_b)
    + d10 S_a + d11 S_b, where rows a and b = a + 1 of ftab hold (P, Q, R, S), nine columns
    each (`kernels._forcing`): rows 0-7 as one vector of eight, row 8 a scalar."""
    _check_contiguous("forcing_rows", ftab, out)
    sig = types.void(ftab, a, h00, h10, h01, h11, d00, d10, d11, out, ooff)

    def codegen(context, builder, signature, args):
        ft = context.make_array(signature.args[0])(context, builder, args[0])
        oa = context.make_array(signature.args[9])(context, builder, args[9])
        row_a = context.cast(builder, args[1], signature.args[1], types.int64)
        weights = [context.cast(builder, args[k], signature.args[k], types.float64) for k in range(2, 9)]
        ooff = context.cast(builder, args[10], signature.args[10], types.int64)
        width = _row_length(builder, ft)
        pa = builder.gep(ft.data, [builder.mul(row_a, width)])
        pb = builder.gep(pa, [width])
        op = builder.gep(oa.data, [ooff])
        fma8, fma1 = _fma8(builder), _fma1(builder)

        def vector(p, col):
            return _load8(builder, builder.gep(p, [ir.Constant(_I64, col)]))

        def scalar(p, col):
            return builder.load(builder.gep(p, [ir.Constant(_I64, col + 8)]))

        for fma, load, wrap in ((fma8, vector, lambda w: _splat8(builder, w)), (fma1, scalar, lambda w: w)):
            w00, w10, w01, w11, e00, e10, e11 = [wrap(w) for w in weights]
            acc = builder.fmul(w00, load(pa, 0))
            acc = builder.call(fma, [w10, load(pa, 9), acc])
            acc = builder.call(fma, [w01, load(pb, 0), acc])
            acc = builder.call(fma, [w11, load(pb, 9), acc])
            acc = builder.call(fma, [e00, builder.fsub(load(pa, 18), load(pb, 18)), acc])
            acc = builder.call(fma, [e10, load(pa, 27), acc])
            acc = builder.call(fma, [e11, load(pb, 27), acc])
            if fma is fma8:
                builder.store(acc, builder.bitcast(op, _V8.as_pointer()), align=8)
            else:
                builder.store(acc, builder.gep(op, [ir.Constant(_I64, 8)]))
        return context.get_dummy_value()

    return sig, codegen
