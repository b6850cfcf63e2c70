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

from railride.engine.layout import N_DOF

#: the rows of q'' beyond the vector of eight: row 8 (the rear bogie's roll) in `mv9_simd`, and
#: from row 9 (the carbody's bending) in the kernels (`kernels._mv9`)
_N2 = 2 * N_DOF

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


def _splat(builder, x, vtype=_V8):
    """A vector of ``vtype`` (eight doubles by default) with every lane x."""
    n = vtype.count
    v = builder.insert_element(ir.Constant(vtype, ir.Undefined), x, ir.Constant(_I32, 0))
    return builder.shuffle_vector(v, ir.Constant(vtype, ir.Undefined), ir.Constant(ir.VectorType(_I32, n), [0] * n))


def _row_length(builder, arr):
    """Elements per row of a C-contiguous 2-D float64 array."""
    return builder.sdiv(cgutils.unpack_tuple(builder, arr.strides, 2)[0], ir.Constant(_I64, 8))


@intrinsic
def mv9_simd(typingctx, AT, x, xf, n_cols, r, roff, out, ooff, idx8, val8, n8):
    """out[ooff + i] = r[roff + i] + sum_j AT[j, i] v[j] for rows i < 9 of q'', v[j] = x[j] for
    j < 2 N_DOF (q, q') and xf[j] beyond (the corner forces); AT is (n_cols, N_DOF). Row 9 on
    (the carbody's bending) is the caller's (`kernels._mv9`).

    Rows 0-7 form one vector of eight. The columns are summed in three independent chains, q,
    q' and the forces from r, added at the end: one chain of 22 multiply-adds
    made the product wait on its own latency. Row 8, a scalar, is summed over its non-zero
    entries only: n8 values val8 in the columns idx8 (a bogie's roll couples to 6 of the 22
    columns; the dense scalar row cost as many instructions as the vector of eight, and
    skipping it made the MR closed loop 6 % faster)."""
    _check_contiguous("mv9_simd", AT, x, xf, r, out, val8)
    sig = types.void(AT, x, xf, n_cols, r, roff, out, ooff, idx8, val8, n8)

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
        zero8 = ir.Constant(_V8, [0.0] * 8)
        ia = context.make_array(signature.args[8])(context, builder, args[8])
        va = context.make_array(signature.args[9])(context, builder, args[9])
        n8 = context.cast(builder, args[10], signature.args[10], types.int64)
        sums = []
        for src, lo, hi, init8 in (
            (xa, ir.Constant(_I64, 0), ir.Constant(_I64, N_DOF), zero8),
            (xa, ir.Constant(_I64, N_DOF), ir.Constant(_I64, _N2), zero8),
            (xfa, ir.Constant(_I64, _N2), nc, _load8(builder, rp)),
        ):
            acc8 = cgutils.alloca_once_value(builder, init8)
            with cgutils.for_range_slice(builder, lo, hi, one, inc=True) as (j, _):
                xj = builder.load(builder.gep(src.data, [j]))
                row = builder.gep(at.data, [builder.mul(j, width)])
                col8 = _load8(builder, row)
                builder.store(builder.call(fma8, [col8, _splat(builder, xj), builder.load(acc8)]), acc8)
            sums.append(builder.load(acc8))
        q8, v8, f8 = sums
        # row 8 over its non-zero columns only (idx8, val8: n8 of them)
        acc1 = cgutils.alloca_once_value(builder, builder.load(builder.gep(rp, [eight])))
        lim = ir.Constant(_I64, _N2)
        with cgutils.for_range_slice(builder, ir.Constant(_I64, 0), n8, one, inc=True) as (k, _):
            j = builder.load(builder.gep(ia.data, [k]))
            j = context.cast(builder, j, signature.args[8].dtype, types.int64)
            src = builder.select(builder.icmp_signed("<", j, lim), xa.data, xfa.data)
            xj = builder.load(builder.gep(src, [j]))
            vj = builder.load(builder.gep(va.data, [k]))
            builder.store(builder.call(fma1, [vj, xj, builder.load(acc1)]), acc1)
        op = builder.gep(oa.data, [oo])
        builder.store(builder.fadd(f8, builder.fadd(q8, v8)), builder.bitcast(op, _V8.as_pointer()), align=8)
        builder.store(builder.load(acc1), builder.gep(op, [eight]))
        return context.get_dummy_value()

    return sig, codegen


@intrinsic
def corner_pairs(typingctx, TT, s, cx, cv):
    """cx[c] = sum_j TT[j, c] s[j] and cv[c] = sum_j TT[j, c] s[N_DOF + j] (c < 4, j < N_DOF): the
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
        for j in range(N_DOF):
            row_ptr = builder.gep(tt.data, [builder.mul(ir.Constant(_I64, j), width)])
            row = builder.load(builder.bitcast(row_ptr, _V4.as_pointer()), align=8)
            both = builder.shuffle_vector(row, ir.Constant(_V4, ir.Undefined), twice)
            q = builder.load(builder.gep(sa.data, [ir.Constant(_I64, j)]))
            qd = builder.load(builder.gep(sa.data, [ir.Constant(_I64, N_DOF + j)]))
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
    """out[ooff + i] (i < N_DOF) = h00 P_a + h10 Q_a + h01 P_b + h11 Q_b + d00 (R_a - R_b)
    + d10 S_a + d11 S_b, where rows a and b = a + 1 of ftab hold (P, Q, R, S), N_DOF columns
    each (`kernels._forcing`): rows 0-7 as one vector of eight, the rows after them scalars."""
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

        def scalar_at(row):
            return lambda p, col: builder.load(builder.gep(p, [ir.Constant(_I64, col + row)]))

        parts = [(fma8, vector, lambda w: _splat(builder, w), None)]
        parts += [(fma1, scalar_at(row), lambda w: w, row) for row in range(8, N_DOF)]
        n = N_DOF
        for fma, load, wrap, row in parts:
            w00, w10, w01, w11, e00, e10, e11 = [wrap(w) for w in weights]
            acc = builder.fmul(w00, load(pa, 0))
            acc = builder.call(fma, [w10, load(pa, n), acc])
            acc = builder.call(fma, [w01, load(pb, 0), acc])
            acc = builder.call(fma, [w11, load(pb, n), acc])
            acc = builder.call(fma, [e00, builder.fsub(load(pa, 2 * n), load(pb, 2 * n)), acc])
            acc = builder.call(fma, [e10, load(pa, 3 * n), acc])
            acc = builder.call(fma, [e11, load(pb, 3 * n), acc])
            if row is None:
                builder.store(acc, builder.bitcast(op, _V8.as_pointer()), align=8)
            else:
                builder.store(acc, builder.gep(op, [ir.Constant(_I64, row)]))
        return context.get_dummy_value()

    return sig, codegen


def _load4_strided(builder, base, start, stride):
    """A vector of four doubles base[start + stride * c], c < 4."""
    v = ir.Constant(_V4, ir.Undefined)
    for c in range(4):
        x = builder.load(builder.gep(base, [ir.Constant(_I64, start + stride * c)]))
        v = builder.insert_element(v, x, ir.Constant(_I32, c))
    return v


@intrinsic
def bouc_wen1_corners(typingctx, P, s, cx, cv, vcmd, conn, y, K, koff):
    """The four corners' Bouc-Wen dampers with n = 1 (`laws.damper_law`, LAW_BOUC_WEN), as
    one vector of four: with z, u the damper states s[2N + 3c], s[2N + 2 + 3c] (N = N_DOF) and
    (x, x') = (cx[c], cv[c]), F = (P0 + P1 u) z + (P2 + P3 u) x' + P4 x, and y[2N + c] = -F conn[c];
    K[koff + 2N + 3c ...] = (z', 0, u') with z' = -P7 |x'| z - P8 x' |z| + P5 x' and
    u' = -P9 (u - vcmd[c])."""
    _check_contiguous("bouc_wen1_corners", P, s, cx, cv, vcmd, conn, y, K)
    sig = types.void(P, s, cx, cv, vcmd, conn, y, K, koff)

    def codegen(context, builder, signature, args):
        pa, sa, xa, va, ca, na, ya, ka = (
            context.make_array(signature.args[i])(context, builder, args[i]) for i in range(8)
        )
        ko = context.cast(builder, args[8], signature.args[8], types.int64)
        fma4 = cgutils.get_or_insert_function(builder.module, ir.FunctionType(_V4, [_V4] * 3), "llvm.fma.v4f64")
        fabs4 = cgutils.get_or_insert_function(builder.module, ir.FunctionType(_V4, [_V4]), "llvm.fabs.v4f64")

        def load4(arr):
            return builder.load(builder.bitcast(arr.data, _V4.as_pointer()), align=8)

        def par(i):
            return _splat(builder, builder.load(builder.gep(pa.data, [ir.Constant(_I64, i)])), _V4)

        z = _load4_strided(builder, sa.data, _N2, 3)
        u = _load4_strided(builder, sa.data, _N2 + 2, 3)
        x, xd = load4(xa), load4(va)
        alpha = builder.call(fma4, [par(1), u, par(0)])
        c0 = builder.call(fma4, [par(3), u, par(2)])
        force = builder.call(fma4, [c0, xd, builder.fmul(par(4), x)])
        force = builder.call(fma4, [alpha, z, force])
        fcar = builder.fmul(builder.fneg(force), load4(na))
        builder.store(fcar, builder.bitcast(builder.gep(ya.data, [ir.Constant(_I64, _N2)]), _V4.as_pointer()), align=8)
        dz = builder.fmul(par(5), xd)
        dz = builder.call(fma4, [builder.fneg(builder.fmul(par(7), builder.call(fabs4, [xd]))), z, dz])
        dz = builder.call(fma4, [builder.fneg(builder.fmul(par(8), xd)), builder.call(fabs4, [z]), dz])
        du = builder.fmul(builder.fneg(par(9)), builder.fsub(u, load4(ca)))
        base = builder.gep(ka.data, [ko])
        zero = ir.Constant(_F64, 0.0)
        for c in range(4):
            idx = ir.Constant(_I32, c)
            builder.store(builder.extract_element(dz, idx), builder.gep(base, [ir.Constant(_I64, _N2 + 3 * c)]))
            builder.store(zero, builder.gep(base, [ir.Constant(_I64, _N2 + 1 + 3 * c)]))
            builder.store(builder.extract_element(du, idx), builder.gep(base, [ir.Constant(_I64, _N2 + 2 + 3 * c)]))
        return context.get_dummy_value()

    return sig, codegen
