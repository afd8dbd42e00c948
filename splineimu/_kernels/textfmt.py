"""Lossless float-to-text kernels: the digits of a table of integer stamps and float64 values.

:func:`format_table` writes a table into a preallocated ``uint8`` buffer; the public layer
(:mod:`splineimu.io.tables`) validates, allocates and runs it in threads. Each float is written
with the shortest decimal of at most 15 significant digits that reads back to the same double,
else with the 17 correctly rounded digits of ``"%.17g"``; stamps as integer nanoseconds or as
``seconds.nanoseconds`` with exactly 9 decimals.

Every kernel is compiled with ``nrt=False`` (no reference counting of the scratch arrays passed
between helpers; see :mod:`splineimu._jit`), so none of them allocates: the caller passes the
output buffer and the scratch arrays (``limbs``: :data:`N_LIMBS` int64, ``dig``: 20 uint8).
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import jit

_LIMB_BITS = 31
_LIMB_MASK = (1 << 31) - 1
N_LIMBS = 40  # 53 + 340 * log2(5) bits (smallest subnormal) < 40 * 31
_POW10_F = np.array([float(10**k) for k in range(23)])  # exact doubles
_POW10_I = np.array([10**k for k in range(19)], dtype=np.int64)
_DIGIT_PAIRS = np.frombuffer("".join(f"{i:02d}" for i in range(100)).encode(), dtype=np.uint8).copy()
_POW5_I = np.array([5**k for k in range(14)], dtype=np.int64)  # 5**13 < 2**31
#: Values at or above this magnitude are formatted in Python (the kernel's integer path
#: needs |x| < 2**63).
KERNEL_MAX_ABS = 9.0e18


@jit(nrt=False)
def _exact_n17(M, E, d, limbs):
    """``round_half_even(M * 2**E * 10**(16 - d))`` for ``16 - d >= 0``, ``M < 2**53``."""
    k = 16 - d
    limbs[0] = M & _LIMB_MASK
    limbs[1] = M >> _LIMB_BITS
    n = 2
    rem = k
    while rem > 0:
        step = 13 if rem >= 13 else rem
        mul = _POW5_I[step]
        carry = 0
        for i in range(n):
            v = limbs[i] * mul + carry
            limbs[i] = v & _LIMB_MASK
            carry = v >> _LIMB_BITS
        while carry > 0:
            limbs[n] = carry & _LIMB_MASK
            carry = carry >> _LIMB_BITS
            n += 1
        rem -= step
    s = E + k
    if s >= 0:
        N = 0
        for i in range(n - 1, -1, -1):
            N = (N << _LIMB_BITS) | limbs[i]
        return N << s
    r = -s
    ql = r // _LIMB_BITS
    qb = r % _LIMB_BITS
    if ql >= n:
        N = 0
    else:
        N = limbs[ql] >> qb
        for i in range(ql + 1, n):
            N = N | (limbs[i] << (_LIMB_BITS * (i - ql) - qb))
    hb = r - 1
    hl = hb // _LIMB_BITS
    hbit = hb % _LIMB_BITS
    half = (limbs[hl] >> hbit) & 1 if hl < n else 0
    sticky = False
    if hl < n and (limbs[hl] & ((1 << hbit) - 1)) != 0:
        sticky = True
    else:
        for i in range(min(hl, n)):
            if limbs[i] != 0:
                sticky = True
                break
    if half == 1 and (sticky or (N & 1) == 1):
        N += 1
    return N


_U100 = np.uint64(100)
_U10 = np.uint64(10)


@jit(nrt=False)
def _digits_into(v, nd, dig):
    """The ``nd`` lowest decimal digits of ``v >= 0`` into ``dig[0:nd]`` (ASCII), two at a time.

    Unsigned arithmetic: a division by a constant is then a multiply and a shift, without the
    sign corrections of Python's floor division (20 % of the formatter's time, measured)."""
    u = np.uint64(v)
    i = nd
    while i >= 2:
        q = u // _U100
        r = u - q * _U100
        dig[i - 1] = _DIGIT_PAIRS[2 * r + np.uint64(1)]
        dig[i - 2] = _DIGIT_PAIRS[2 * r]
        u = q
        i -= 2
    if i == 1:
        dig[0] = np.uint8(48) + np.uint8(u % _U10)


@jit(nrt=False)
def _n_digits(v):
    n = 1
    while n < 19 and v >= _POW10_I[n]:
        n += 1
    return n


@jit(nrt=False)
def _write_uint(v, out, pos):
    """Decimal digits of ``v >= 0``."""
    n = _n_digits(v)
    _digits_into(v, n, out[pos:pos + n])
    return pos + n


@jit(nrt=False)
def _emit(N, nd, d, neg, out, pos, dig):
    """Write ``+-d1.d2...d_nd * 10**d`` (``N`` has exactly ``nd`` digits), shortest form."""
    _digits_into(N, nd, dig)
    while nd > 1 and dig[nd - 1] == 48:
        nd -= 1
    if neg:
        out[pos] = 45
        pos += 1
    if 0 <= d < 17:
        if nd <= d + 1:
            for i in range(nd):
                out[pos + i] = dig[i]
            pos += nd
            for _ in range(d + 1 - nd):
                out[pos] = 48
                pos += 1
            return pos
        for i in range(d + 1):
            out[pos + i] = dig[i]
        pos += d + 1
        out[pos] = 46
        pos += 1
        for i in range(d + 1, nd):
            out[pos] = dig[i]
            pos += 1
        return pos
    if -5 <= d < 0:
        out[pos] = 48
        out[pos + 1] = 46
        pos += 2
        for _ in range(-d - 1):
            out[pos] = 48
            pos += 1
        for i in range(nd):
            out[pos + i] = dig[i]
        return pos + nd
    # scientific: d1[.d2...]e+-XX
    out[pos] = dig[0]
    pos += 1
    if nd > 1:
        out[pos] = 46
        pos += 1
        for i in range(1, nd):
            out[pos] = dig[i]
            pos += 1
    out[pos] = 101
    pos += 1
    if d < 0:
        out[pos] = 45
        d = -d
    else:
        out[pos] = 43
    pos += 1
    if d < 10:
        out[pos] = 48
        pos += 1
    return _write_uint(d, out, pos)


@jit(nrt=False)
def _round_scaled(a, P):
    """``round_half_even(a * P)`` exactly, for ``a * P < 2**62`` with ``P`` a power of ten.

    Dekker's product gives ``a * P = p + err`` exactly (``p`` the rounded product, ``err``
    a double); at or above 2**53 ``p`` is an integer, so the rounding is decided by ``err``
    alone, compared with exactly representable half-integers. Below 2**53 the result only
    has to be small enough for the caller to ask for one more digit.
    """
    p = a * P
    if p < 9007199254740992.0:
        return np.int64(p)
    c = 134217729.0 * a  # 2**27 + 1: Veltkamp splitting into 26 + 27 bits
    ah = c - (c - a)
    al = a - ah
    c = 134217729.0 * P
    bh = c - (c - P)
    bl = P - bh
    err = ((ah * bh - p) + ah * bl + al * bh) + al * bl
    fl = math.floor(err)
    N = np.int64(p) + np.int64(fl)
    half = fl + 0.5
    if err > half or (err == half and (N & 1) == 1):
        N += 1
    return N


@jit(nrt=False)
def _write_float(x, limbs, dig, out, pos):
    """Shortest of 15 digits if it round-trips, else 17 correctly rounded digits."""
    if x == 0.0:
        if math.copysign(1.0, x) < 0.0:
            out[pos] = 45
            pos += 1
        out[pos] = 48
        return pos + 1
    neg = x < 0.0
    a = -x if neg else x
    d = int(math.floor(math.log10(a)))
    # fast path: 15 significant digits in double arithmetic, exact when |k| <= 22
    k = 14 - d
    for _ in range(3):
        if k < -22 or k > 22:
            break
        y = a * _POW10_F[k] if k >= 0 else a / _POW10_F[-k]
        Nf = np.rint(y)
        if Nf >= 1e15:
            d += 1
            k -= 1
            continue
        if Nf < 1e14:
            d -= 1
            k += 1
            continue
        back = Nf / _POW10_F[k] if k >= 0 else Nf * _POW10_F[-k]
        if back == a:
            return _emit(np.int64(Nf), 15, d, neg, out, pos, dig)
        break
    # 17 digits, usual range: a * 10**k (10**k exact) as an exact double-double
    k = 16 - d
    for _ in range(3):
        if k < 0 or k > 22:
            break
        N = _round_scaled(a, _POW10_F[k])
        if N >= 100000000000000000:
            k -= 1
        elif N < 10000000000000000:
            k += 1
        else:
            return _emit(N, 17, 16 - k, neg, out, pos, dig)
    # exact path: 17 digits, round-half-even, from the binary significand
    m, e = math.frexp(a)
    M = np.int64(m * 9007199254740992.0)  # m * 2**53, exact
    E = e - 53
    d = int(math.floor(math.log10(a)))
    for _ in range(4):
        if 16 - d >= 0:
            N = _exact_n17(M, E, d, limbs)
        else:
            X = np.int64(a)  # a >= 1e17 > 2**53: an integer, and < 2**63 (checked by caller)
            div = _POW10_I[d - 16]
            N = X // div
            r2 = 2 * (X % div)
            if r2 > div or (r2 == div and (N & 1) == 1):
                N += 1
        if N >= 100000000000000000:
            d += 1
        elif N < 10000000000000000:
            d -= 1
        else:
            break
    return _emit(N, 17, d, neg, out, pos, dig)


@jit(nrt=False)
def _write_stamp(t, stamp_mode, out, pos):
    if t < 0:
        out[pos] = 45
        pos += 1
        t = -t
    if stamp_mode == 0:
        return _write_uint(t, out, pos)
    pos = _write_uint(t // 1000000000, out, pos)
    out[pos] = 46
    _digits_into(t % 1000000000, 9, out[pos + 1:pos + 10])
    return pos + 10


def max_bytes(n_rows: int, n_cols: int) -> int:
    """Size of an output buffer that any table of this shape fits in (a stamp of at most 23
    bytes, then per value a separator and at most 26 bytes, a newline)."""
    return n_rows * (23 + 27 * n_cols) + 1


def scratch():
    """Fresh scratch arrays ``(limbs, dig)`` for :func:`format_table` (one pair per thread)."""
    return np.zeros(N_LIMBS, np.int64), np.zeros(20, np.uint8)


@jit(nrt=False, nogil=True)
def format_table(t_ns, values, sep, stamp_mode, out, limbs, dig):
    """Write the rows ``stamp sep v0 sep v1 ... \\n`` into ``out``; return the bytes written.

    ``t_ns`` (N,) int64; ``values`` (N, C) finite float64 below :data:`KERNEL_MAX_ABS`; ``sep``
    the separator byte (uint8); ``stamp_mode`` 0 for integer ns, 1 for ``seconds.nanoseconds``;
    ``out`` uint8 of at least :func:`max_bytes`; ``limbs`` and ``dig`` scratch (:func:`scratch`).
    """
    pos = 0
    n = values.shape[0]
    c = values.shape[1]
    for i in range(n):
        pos = _write_stamp(t_ns[i], stamp_mode, out, pos)
        for j in range(c):
            out[pos] = sep
            pos += 1
            pos = _write_float(values[i, j], limbs, dig, out, pos)
        out[pos] = 10
        pos += 1
    return pos
