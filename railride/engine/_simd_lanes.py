"""Vector kernels of the lane stepper (`railride.engine.lanes.run_lanes`), as numba intrinsics.

The lane stepper advances LANES samples at once: every per-sample array holds one row of
LANES doubles per quantity (lane-innermost), and each intrinsic here treats a row as one
vector ``<LANES x double>``, so that one instruction advances every lane. Written as LLVM IR
for the reason `railride.engine._simd` gives: numba has no vector type, and LLVM left the plain lane
loops scalar (it cannot rule out that the arrays alias): the q'' product ten times slower
than here (docs/performance.md).

Every array argument must be C-contiguous float64 with LANES columns (2-D) or LANES items
(1-D lane vectors), except the int64 index lists; the kernel that calls them guarantees that.
"""

from __future__ import annotations

from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.core.errors import TypingError
from numba.extending import intrinsic

from railride.engine._simd import _splat as splat

#: samples advanced together; 8 doubles fill one AVX-512 register (two AVX2 ones). Measured
#: against 4 and 16 in docs/performance.md. After changing it delete railride/__pycache__/kernels*.nb*
#: (numba's cache does not track this file).
LANES = 8

_I64 = ir.IntType(64)
_F64 = ir.DoubleType()
_VL = ir.VectorType(_F64, LANES)


def _check(name, *arrays):
    for a in arrays:
        if not isinstance(a, types.Array) or a.layout != "C" or a.dtype != types.float64:
            raise TypingError(f"{name}: needs C-contiguous float64 arrays, got {a}")


def _check_index(name, *arrays):
    for a in arrays:
        if not isinstance(a, types.Array) or a.ndim != 1 or a.dtype != types.int64:
            raise TypingError(f"{name}: needs 1-D int64 index arrays, got {a}")


def _fma(builder):
    return cgutils.get_or_insert_function(builder.module, ir.FunctionType(_VL, [_VL] * 3), f"llvm.fma.v{LANES}f64")


def _row(builder, data, row):
    """Pointer to the lane vector of row ``row`` (an i64) of a (rows, LANES) array."""
    p = builder.gep(data, [builder.mul(row, ir.Constant(_I64, LANES))])
    return builder.bitcast(p, _VL.as_pointer())


def _load(builder, data, row):
    return builder.load(_row(builder, data, row), align=8)


def _store(builder, value, data, row):
    builder.store(value, _row(builder, data, row), align=8)


def _i64(context, builder, sig, args, k):
    return context.cast(builder, args[k], sig.args[k], types.int64)


def _data(context, builder, sig, args, k):
    return context.make_array(sig.args[k])(context, builder, args[k]).data


@intrinsic
def lanes_spmv(typingctx, ptr, col, val, uniform, src, init, ioff, out, ooff):
    """out[ooff + i] = init[ioff + i] + sum_k val[k] src[col[k]] over ptr[i] <= k < ptr[i + 1],
    for the rows i < len(ptr) - 1, lane by lane: a product restricted to its non-zero structure
    (compressed rows), each term one vector multiply-add. With ``uniform`` (every lane's entries
    alike) each entry is read once from lane 0 and broadcast: half the vector loads, the same
    arithmetic."""
    _check("lanes_spmv", val, src, init, out)
    _check_index("lanes_spmv", ptr, col)
    sig = types.void(ptr, col, val, uniform, src, init, ioff, out, ooff)

    def codegen(context, builder, signature, args):
        pa = context.make_array(signature.args[0])(context, builder, args[0])
        pd = pa.data
        cd = _data(context, builder, signature, args, 1)
        vd = _data(context, builder, signature, args, 2)
        uni = context.cast(builder, args[3], signature.args[3], types.boolean)
        sd = _data(context, builder, signature, args, 4)
        idata = _data(context, builder, signature, args, 5)
        od = _data(context, builder, signature, args, 7)
        io = _i64(context, builder, signature, args, 6)
        oo = _i64(context, builder, signature, args, 8)
        fma = _fma(builder)
        one = ir.Constant(_I64, 1)
        two = ir.Constant(_I64, 2)
        n_rows = builder.sub(cgutils.unpack_tuple(builder, pa.shape, 1)[0], one)

        def broadcast(k):
            return _splat(builder, builder.load(builder.bitcast(_row(builder, vd, k), _F64.as_pointer())))

        def vector(k):
            return _load(builder, vd, k)

        def rows(entry):
            with cgutils.for_range(builder, n_rows) as loop:
                # two chains, even and odd terms, added at the end: one chain waits on its latency
                i = loop.index
                acc0 = cgutils.alloca_once_value(builder, _load(builder, idata, builder.add(io, i)))
                acc1 = cgutils.alloca_once_value(builder, ir.Constant(_VL, [0.0] * LANES))
                k0 = builder.load(builder.gep(pd, [i]))
                k1 = builder.load(builder.gep(pd, [builder.add(i, one)]))

                def term(acc, k):
                    j = builder.load(builder.gep(cd, [k]))
                    builder.store(builder.call(fma, [entry(k), _load(builder, sd, j), builder.load(acc)]), acc)

                with cgutils.for_range(builder, builder.sdiv(builder.sub(k1, k0), two)) as pair:
                    k = builder.add(k0, builder.mul(pair.index, two))
                    term(acc0, k)
                    term(acc1, builder.add(k, one))
                odd = builder.icmp_signed("!=", builder.srem(builder.sub(k1, k0), two), ir.Constant(_I64, 0))
                with builder.if_then(odd):
                    term(acc0, builder.sub(k1, one))
                _store(builder, builder.fadd(builder.load(acc0), builder.load(acc1)), od, builder.add(oo, i))

        with builder.if_else(uni) as (then, otherwise):
            with then:
                rows(broadcast)
            with otherwise:
                rows(vector)
        return context.get_dummy_value()

    return sig, codegen


@intrinsic
def lanes_axpy(typingctx, dst, doff, a, aoff, c, b, boff, n):
    """dst[doff + r] = a[aoff + r] + c * b[boff + r] for r < n; c is one lane vector."""
    _check("lanes_axpy", dst, a, c, b)
    sig = types.void(dst, doff, a, aoff, c, b, boff, n)

    def codegen(context, builder, signature, args):
        dd = _data(context, builder, signature, args, 0)
        ad = _data(context, builder, signature, args, 2)
        cv = builder.load(builder.bitcast(_data(context, builder, signature, args, 4), _VL.as_pointer()), align=8)
        bd = _data(context, builder, signature, args, 5)
        do, ao, bo, nn = (_i64(context, builder, signature, args, k) for k in (1, 3, 6, 7))
        fma = _fma(builder)
        with cgutils.for_range(builder, nn) as loop:
            r = loop.index
            v = builder.call(fma, [cv, _load(builder, bd, builder.add(bo, r)), _load(builder, ad, builder.add(ao, r))])
            _store(builder, v, dd, builder.add(do, r))
        return context.get_dummy_value()

    return sig, codegen


@intrinsic
def lanes_rk4(typingctx, s, off, K, stride, n, h6, act):
    """s[off + r] += h6 (K1 + 2 K2 + 2 K3 + K4)[off + r] for r < n, where stage j's rates are
    rows off + r + j * stride of K, in the lanes where act != 0 (the others keep s)."""
    _check("lanes_rk4", s, K, h6, act)
    sig = types.void(s, off, K, stride, n, h6, act)

    def codegen(context, builder, signature, args):
        sd = _data(context, builder, signature, args, 0)
        kd = _data(context, builder, signature, args, 2)
        hv = builder.load(builder.bitcast(_data(context, builder, signature, args, 5), _VL.as_pointer()), align=8)
        av = builder.load(builder.bitcast(_data(context, builder, signature, args, 6), _VL.as_pointer()), align=8)
        mask = builder.fcmp_unordered("!=", av, ir.Constant(_VL, [0.0] * LANES))
        o, st, nn = (_i64(context, builder, signature, args, k) for k in (1, 3, 4))
        two = ir.Constant(_VL, [2.0] * LANES)
        fma = _fma(builder)
        with cgutils.for_range(builder, nn) as loop:
            r = builder.add(o, loop.index)
            k1 = _load(builder, kd, r)
            k2 = _load(builder, kd, builder.add(r, st))
            k3 = _load(builder, kd, builder.add(r, builder.mul(st, ir.Constant(_I64, 2))))
            k4 = _load(builder, kd, builder.add(r, builder.mul(st, ir.Constant(_I64, 3))))
            total = builder.fadd(builder.call(fma, [two, builder.fadd(k2, k3), k1]), k4)
            old = _load(builder, sd, r)
            new = builder.call(fma, [hv, total, old])
            _store(builder, builder.select(mask, new, old), sd, r)
        return context.get_dummy_value()

    return sig, codegen


@intrinsic
def lanes_move(typingctx, dst, doff, src, soff, n, act):
    """dst[doff + r] = src[soff + r] for r < n, in the lanes where act != 0."""
    _check("lanes_move", dst, src, act)
    sig = types.void(dst, doff, src, soff, n, act)

    def codegen(context, builder, signature, args):
        dd = _data(context, builder, signature, args, 0)
        sd = _data(context, builder, signature, args, 2)
        av = builder.load(builder.bitcast(_data(context, builder, signature, args, 5), _VL.as_pointer()), align=8)
        mask = builder.fcmp_unordered("!=", av, ir.Constant(_VL, [0.0] * LANES))
        do, so, nn = (_i64(context, builder, signature, args, k) for k in (1, 3, 4))
        with cgutils.for_range(builder, nn) as loop:
            r = loop.index
            d = builder.add(do, r)
            v = builder.select(mask, _load(builder, sd, builder.add(so, r)), _load(builder, dd, d))
            _store(builder, v, dd, d)
        return context.get_dummy_value()

    return sig, codegen


def _intrinsic_fn(builder, name, n_args):
    return cgutils.get_or_insert_function(builder.module, ir.FunctionType(_VL, [_VL] * n_args), f"{name}.v{LANES}f64")


def _splat(builder, x):
    return splat(builder, x, _VL)


@intrinsic
def lanes_mr_damper(typingctx, spencer, P, CC, ST, rf, rd, VC, CONN, K, kb):
    """The MR damper law of `railride.engine.laws.damper_law` at the four corners, every lane at
    once: Bouc-Wen, or Spencer where ``spencer``. Corner c's deflection and rate are CC[c] and
    CC[4 + c], its states (z, y, u) ST[rd + 3c ...], its command VC[c]; ST[rf + c] receives the
    force on the carbody -F CONN[c] and K[kb + rd + 3c ...] the rates (z', y', u'). P holds the
    parameters (`Damper.pack()`), the same in every lane."""
    _check("lanes_mr_damper", P, CC, ST, VC, CONN, K)
    sig = types.void(spencer, P, CC, ST, rf, rd, VC, CONN, K, kb)

    def codegen(context, builder, signature, args):
        is_spencer = context.cast(builder, args[0], signature.args[0], types.boolean)
        pdata = _data(context, builder, signature, args, 1)
        cc, st, vc, conn, kk = (_data(context, builder, signature, args, k) for k in (2, 3, 6, 7, 8))
        rf_, rd_, kb_ = (_i64(context, builder, signature, args, k) for k in (4, 5, 9))
        fma = _fma(builder)
        fabs = _intrinsic_fn(builder, "llvm.fabs", 1)
        vpow = _intrinsic_fn(builder, "llvm.pow", 2)
        p = [builder.load(builder.gep(pdata, [ir.Constant(_I64, i)])) for i in range(16)]
        sp = [_splat(builder, v) for v in p]
        zero = ir.Constant(_VL, [0.0] * LANES)
        one = ir.Constant(_VL, [1.0] * LANES)
        n = p[6]
        # |z|^(n-1) by the exponent, uniform over the lanes: branch once, as the scalar law does
        n_is_1 = builder.fcmp_ordered("==", n, ir.Constant(_F64, 1.0))
        n_is_2 = builder.fcmp_ordered("==", n, ir.Constant(_F64, 2.0))

        def zpow(az):
            slot = cgutils.alloca_once_value(builder, one)
            with builder.if_then(builder.not_(n_is_1)):
                with builder.if_else(n_is_2) as (two, other):
                    with two:
                        builder.store(az, slot)
                    with other:
                        builder.store(builder.call(vpow, [az, builder.fsub(sp[6], one)]), slot)
            return builder.load(slot)

        def bouc_wen_rate(z, w):  # -gamma |w| z |z|^(n-1) - beta w |z|^(n-1) |z| + A w
            az = builder.call(fabs, [z])
            zn1 = zpow(az)
            a = builder.fmul(builder.fmul(builder.fmul(sp[7], builder.call(fabs, [w])), z), zn1)
            b = builder.fmul(builder.fmul(builder.fmul(sp[8], w), zn1), az)
            return builder.fsub(builder.fsub(builder.fmul(sp[5], w), a), b)

        def row(base, off):
            return builder.add(base, ir.Constant(_I64, off))

        for c in range(4):
            x = _load(builder, cc, ir.Constant(_I64, c))
            xd = _load(builder, cc, ir.Constant(_I64, 4 + c))
            b = row(rd_, 3 * c)
            z = _load(builder, st, b)
            y = _load(builder, st, row(b, 1))
            u = _load(builder, st, row(b, 2))
            v = _load(builder, vc, ir.Constant(_I64, c))
            alpha = builder.call(fma, [sp[1], u, sp[0]])
            c0 = builder.call(fma, [sp[3], u, sp[2]])
            du = builder.fmul(builder.fsub(zero, sp[9]), builder.fsub(u, v))
            f_slot = cgutils.alloca_once_value(builder, zero)
            dz_slot = cgutils.alloca_once_value(builder, zero)
            dy_slot = cgutils.alloca_once_value(builder, zero)
            with builder.if_else(is_spencer) as (then, otherwise):
                with then:
                    c1 = builder.call(fma, [sp[13], u, sp[12]])
                    num = builder.fadd(
                        builder.fadd(builder.fmul(alpha, z), builder.fmul(c0, xd)),
                        builder.fmul(sp[4], builder.fsub(x, y)),
                    )
                    dy = builder.fdiv(num, builder.fadd(c0, c1))
                    builder.store(dy, dy_slot)
                    builder.store(bouc_wen_rate(z, builder.fsub(xd, dy)), dz_slot)
                    builder.store(builder.fadd(builder.fmul(c1, dy), builder.fmul(sp[14], x)), f_slot)
                with otherwise:
                    builder.store(bouc_wen_rate(z, xd), dz_slot)
                    force = builder.fadd(
                        builder.fadd(builder.fmul(c0, xd), builder.fmul(sp[4], x)), builder.fmul(alpha, z)
                    )
                    builder.store(force, f_slot)
            f = builder.load(f_slot)
            _store(
                builder,
                builder.fmul(builder.fsub(zero, f), _load(builder, conn, ir.Constant(_I64, c))),
                st,
                row(rf_, c),
            )
            kr = builder.add(kb_, b)
            _store(builder, builder.load(dz_slot), kk, kr)
            _store(builder, builder.load(dy_slot), kk, row(kr, 1))
            _store(builder, du, kk, row(kr, 2))
        return context.get_dummy_value()

    return sig, codegen
