"""Certified signs of floating-point polynomial expressions (pure JAX).

A polynomial quantity ``P`` is written once as a Python function of its inputs and a ``sub``
argument, and evaluated twice by that code: as written (``sub`` is subtraction), giving ``fl(P)``,
and with every input replaced by its absolute value and every subtraction by an addition, giving
``fl(P_abs)``.  The error bound is **derived from the expression itself** by :func:`error_model`,
which runs the same function on symbolic stand-ins (:class:`_Tracer`):

* every ``+``, ``-`` and ``*`` (and every multiplication by a constant that is not a power of two)
  rounds once: ``fl(x o y) = (x o y)(1 + d) + e``, ``|d| <= u``, ``|e| <= tiny`` (``e`` covers results
  flushed to zero below the smallest normal number: XLA on CPU flushes subnormals; where the result
  is normal, ``e = 0``).  Fused multiply-add only removes roundings, so the bounds hold with or
  without FMA contraction.  XLA on CPU also reads subnormal *inputs* as zero (denormals-are-zero,
  jitted or not): every input is taken as known within ``tiny`` (one ``e`` of its own), and
  :func:`structural_zero` reads zeros from the bits;
* the *rounding count* ``n`` of the expression is the largest number of factors ``(1 + d)`` in any
  monomial of ``fl(P)``: ``max(n_x, n_y) + 1`` for a sum, ``n_x + n_y + 1`` for a product;
* the *underflow floor* ``E`` (in units of ``tiny``) bounds the absolute error from the ``e`` terms,
  given magnitude bounds of the inputs (the callers scale every input to ``|x| <= bound``):
  ``E = (E_x + E_y)(1 + u) + 1`` for a sum and ``(E_x M_y + E_y M_x + E_x E_y)(1 + u) + 1`` for a
  product, ``M`` the magnitude bounds (themselves inflated by ``1 + gamma_n``).

Then (Higham, *Accuracy and Stability of Numerical Algorithms*, 2nd ed., Lemma 3.1 and §3.1)
``|fl(P) - P| <= gamma_n P_abs + E tiny`` with ``gamma_n = n u / (1 - n u)``, and the computed
``A = fl(P_abs) >= (1 - gamma_n) P_abs - E tiny``, so ``|fl(P) - P| <= gamma_n / (1 - gamma_n)
(A + E tiny) + E tiny =: bound``; the bound is itself evaluated with a relative margin of ``8 u``.
A sign is *certified* when ``|fl(P)| > bound``; otherwise it is ``UNKNOWN``.  Non-finite values are
never certified.  An exact zero is certified only structurally: where every monomial of the
expression has an input that is exactly zero (:func:`structural_zero`), or where the caller knows it.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp

from atlas.core.verdicts import UNKNOWN_SIGN

#: sign code for "floating point could not certify the sign" (:data:`atlas.core.verdicts.UNKNOWN_SIGN`)
UNKNOWN = UNKNOWN_SIGN

#: dtype of sign codes inside the kernels: int32, the lane width of float32 vectors (int8 codes
#: cost the packed kernel 5-15 % in conversions between lane widths; verdicts are stored as int8)
CODE = jnp.int32

#: magnitude bound assumed for every input of :func:`evaluate_certified` unless told otherwise
INPUT_BOUND = 2.0


def gamma(n: int, dtype) -> float:
    u = float(jnp.finfo(dtype).eps) / 2.0
    return n * u / (1.0 - n * u)


class _Tracer:
    """Symbolic float: rounding count ``n``, magnitude bound ``mag``, underflow floor ``err``."""

    __slots__ = ("n", "mag", "err", "u")

    def __init__(self, n, mag, err, u):
        self.n, self.mag, self.err, self.u = n, mag, err, u

    @staticmethod
    def _lift(x, like):
        if isinstance(x, _Tracer):
            return x
        v = abs(float(x))
        if float(x) != int(x):  # pragma: no cover - expressions use integer constants only
            raise TypeError("expression constants must be integers")
        return _Tracer(0, v, 0.0, like.u)

    def _sum(self, other):
        o = self._lift(other, self)
        n = max(self.n, o.n) + 1
        return _Tracer(n, self.mag + o.mag, (self.err + o.err) * (1 + self.u) + 1, self.u)

    def _prod(self, other):
        o = self._lift(other, self)
        if o.n == 0 and o.err == 0 and not isinstance(other, _Tracer):
            c = o.mag  # an integer constant: exact if a power of two (no overflow: checked later)
            exact = c >= 1 and float(c).hex().startswith("0x1.0000000000000p")
            n = self.n + (0 if exact else 1)
            err = self.err * c * (1 + self.u) + (0 if exact else 1)
            return _Tracer(n, self.mag * c, err, self.u)
        n = self.n + o.n + 1
        ma, mb = self._inflated(), o._inflated()
        err = (self.err * mb + o.err * ma + self.err * o.err) * (1 + self.u) + 1
        return _Tracer(n, self.mag * o.mag, err, self.u)

    def _inflated(self):
        g = self.n * self.u / (1 - self.n * self.u)
        return self.mag * (1 + g)

    __add__ = __radd__ = __sub__ = __rsub__ = _sum
    __mul__ = __rmul__ = _prod

    def __neg__(self):
        return self

    def __pow__(self, k):
        out = self
        for _ in range(int(k) - 1):
            out = out * self
        return out


def _add(a, b):
    return a + b


@functools.cache
def error_model(
    fn, n_args: int, dtype_name: str, bounds: tuple | None = None, rounded: tuple | None = None
) -> tuple[int, float]:
    """``(n, E)`` of expression ``fn`` (see the module docstring): rounding count and underflow
    floor in units of the smallest normal number, for inputs bounded by ``bounds`` (default
    :data:`INPUT_BOUND` each).  ``rounded`` (one count per input, default 0): an input that
    stands for an exact quantity ``X`` with ``x = X (1 + theta_k)``, ``|theta_k| <= gamma_k``
    (``k`` roundings), so that the bound covers ``P`` at the exact ``X``."""
    u = float(jnp.finfo(dtype_name).eps) / 2.0
    bounds = bounds or (INPUT_BOUND,) * n_args
    rounded = rounded or (0,) * n_args
    # err 1.0: an input may be subnormal, which XLA on CPU reads as zero (module docstring)
    t = fn(*(_Tracer(k, float(b), 1.0, u) for b, k in zip(bounds, rounded)), sub=_add)
    return t.n, t.err


def certified_sign(value, abs_value, exact_zero=None, n: int = 0, floor: float = 0.0):
    """Sign code in {-1, 0, +1, UNKNOWN} (:data:`CODE`) of the exact quantity behind ``value``.

    Parameters
    ----------
    value : array
        Floating-point evaluation of the quantity.
    abs_value : array
        Evaluation of the same expression on absolute values with additions only.
    exact_zero : bool array, optional
        Where the caller knows the exact quantity is zero (structural zero).
    n, floor : int, float
        Rounding count and underflow floor (units of ``tiny``) of the expression
        (:func:`error_model`).
    """
    dtype = value.dtype
    u = float(jnp.finfo(dtype).eps) / 2.0
    g = gamma(n, dtype)
    tiny = float(jnp.finfo(dtype).tiny)
    e = floor * tiny
    bound = (g / (1.0 - g) * (1 + 8 * u)) * (abs_value + e) + e * (1 + 8 * u)
    ok = jnp.isfinite(value) & jnp.isfinite(bound)
    s = jnp.where(value > bound, 1, jnp.where(value < -bound, -1, UNKNOWN))
    s = jnp.where(ok, s, UNKNOWN)
    if exact_zero is not None:
        s = jnp.where(exact_zero, 0, s)
    return s.astype(CODE)


def evaluate_certified(
    fn,
    *args,
    exact_zero=None,
    bounds: tuple | None = None,
    majorants=None,
    zeros: bool = True,
    rounded: tuple | None = None,
):
    """Evaluate ``fn(*args, sub)`` with its certified sign; returns ``(value, abs_value, sign)``.

    Every input must satisfy ``|x| <= bound`` (``bounds``, default :data:`INPUT_BOUND`): the
    underflow floor is derived from these bounds (:func:`error_model`).  ``majorants`` (one per
    input, ``>= |x|``; scalars allowed) replace ``|x|`` in ``abs_value``: ``P_abs`` is monotone in
    every ``|x|``, so the bound stays valid, is looser, and costs almost nothing where the
    majorants are constants or per-axis arrays (the compiler folds the ones).  ``zeros=False``
    skips the structural zeros (:func:`structural_zero`; an exact zero is then ``UNKNOWN``) for
    callers that read only certified nonzero signs: one evaluation of ``fn`` per point less.
    ``rounded``: inputs that are themselves rounded values (:func:`error_model`), e.g.
    :func:`det2_accurate`.
    """
    dtype = jnp.result_type(*args)
    n, floor = error_model(fn, len(args), jnp.dtype(dtype).name, bounds, rounded)
    value = fn(*args, sub=jnp.subtract)
    if majorants is None:
        majorants = [jnp.abs(a) for a in args]
    abs_value = fn(*(jnp.asarray(m, dtype) for m in majorants), sub=jnp.add)
    if zeros:
        zero = structural_zero(fn, *args)
        exact_zero = zero if exact_zero is None else (exact_zero | zero)
    return value, abs_value, certified_sign(value, abs_value, exact_zero, n=n, floor=floor)


def structural_zero(fn, *args):
    """``True`` where every monomial of ``fn`` as written has an input that is exactly zero.

    ``fn`` is evaluated on the indicators ``x != 0`` (0 or 1) with additions only: a sum of
    non-negative small integers, computed exactly, that is zero iff each monomial has a zero
    factor, so the exact value is zero (underflow cannot fake it, unlike ``abs_value == 0``).
    This certifies the exact zeros of the axis lines (``s1 = 0``, ``c2 = 0``) and of ``q_j = 0``.
    The indicators come from the bits (:func:`nonzero`): a subnormal input is not a zero.
    """
    dtype = jnp.result_type(*args)
    ind = [nonzero(a).astype(dtype) for a in args]
    return fn(*ind, sub=jnp.add) == 0


def det2(ux, uy, vx, vy, *, sub=jnp.subtract):
    """``ux vy - uy vx`` (the cross product of two plane vectors)."""
    return sub(ux * vy, uy * vx)


def det2_sign(ux, uy, vx, vy):
    """Sign of ``ux vy - uy vx`` for direction vectors (components of magnitude <= 1), exact.

    float32: the products are formed exactly in float64 (24 + 24 bits < 53), and the rounded
    difference of two floats has the exact sign.  float64: integer arithmetic on the mantissas
    (:func:`_det2_sign_float64`); ``UNKNOWN`` only where an input is subnormal or not finite.
    float32 without float64 (``jax_enable_x64`` off): certified by the error bound, identical or
    opposite vectors an exact zero.
    """
    if ux.dtype == jnp.float64:
        return _det2_sign_float64(ux, uy, vx, vy)
    if has_float64():
        wide = [a.astype(jnp.float64) for a in (ux, uy, vx, vy)]
        d = det2(*wide)
        return jnp.sign(d).astype(CODE)
    return det2_sign_bounded(ux, uy, vx, vy)


def det2_sign_bounded(ux, uy, vx, vy):
    """Sign of ``ux vy - uy vx`` certified by its float error bound only (``UNKNOWN`` where
    ``|det| <~ 2 u (|ux vy| + |uy vx|)``); identical or opposite vectors an exact zero.  The
    fallback of :func:`det2_sign` for float32 without float64."""
    same = ((ux == vx) & (uy == vy)) | ((ux == -vx) & (uy == -vy))
    value = det2(ux, uy, vx, vy)
    abs_value = det2(jnp.abs(ux), jnp.abs(uy), jnp.abs(vx), jnp.abs(vy), sub=jnp.add)
    n, floor = error_model(det2, 4, jnp.dtype(value.dtype).name, (1.0, 1.0, 1.0, 1.0))
    return certified_sign(value, abs_value, exact_zero=same | (abs_value == 0), n=n, floor=floor)


_LOW52, _LOW26 = (1 << 52) - 1, (1 << 26) - 1


def _float64_parts(x):
    """``(sign, m, e, exact)`` of float64 ``x`` from its bits: ``x = sign m 2^e`` with the 53-bit
    integer mantissa ``m``, where ``exact`` (zero or a normal number; the bits, not a float
    comparison, so a flush of subnormals to zero cannot fake a zero)."""
    bits = jax.lax.bitcast_convert_type(x, jnp.int64)
    mag = bits & ((1 << 63) - 1)
    expo = mag >> 52
    zero = ~nonzero(x)  # not ``mag == 0``: LLVM folds that into ``x == 0.0`` (:func:`nonzero`)
    sign = jnp.where(zero, 0, jnp.where(bits < 0, -1, 1)).astype(CODE)
    exact = zero | ((expo > 0) & (expo < 0x7FF))
    return sign, (mag & _LOW52) | (1 << 52), expo - 1075, exact


def _mantissa_product(ma, mb):
    """The exact product of two 53-bit integers as ``(hi, lo)``: ``hi 2^52 + lo``, ``lo < 2^52``
    (26/27-bit halves: every partial product fits in int64)."""
    ha, la, hb, lb = ma >> 26, ma & _LOW26, mb >> 26, mb & _LOW26
    mid = ha * lb + la * hb
    lo = la * lb + ((mid & _LOW26) << 26)
    return ha * hb + (mid >> 26) + (lo >> 52), lo & _LOW52


def _doubled(hi, lo, k):
    """``(hi, lo)`` times ``2^k``, ``k`` in {0, 1, 2, 3}."""
    return (hi << k) | (lo >> (52 - k)), (lo << k) & _LOW52


def _integer_difference(ux, uy, vx, vy):
    """``p - q`` (``p = ux vy``, ``q = uy vx``) in integers where it can cancel.

    Returns ``(near, high, low, e0, sp, sq, ep, eq, exact)``: the signs and exponents of ``p``
    and ``q`` (``p = sp m_p 2^ep``, mantissa products in ``[2^104, 2^106)``), ``exact`` where every
    input is zero or normal, and ``near`` where both are nonzero with exponents at most 3 apart;
    there ``p - q = (high 2^52 + low) 2^e0`` exactly, ``0 <= low < 2^52`` (no rounding, so no
    compiler contraction can change it).  Elsewhere one of ``|p|, |q|`` exceeds 4 times the
    other, or one is zero.
    """
    sign, m, e, exact = zip(*(_float64_parts(a) for a in (ux, uy, vx, vy)))
    sp = (sign[0] * sign[3]).astype(jnp.int64)
    sq = (sign[1] * sign[2]).astype(jnp.int64)
    ep, eq = e[0] + e[3], e[1] + e[2]
    e0 = jnp.minimum(ep, eq)
    near = (sp != 0) & (sq != 0) & (jnp.abs(ep - eq) <= 3)
    hp, lp = _doubled(*_mantissa_product(m[0], m[3]), jnp.clip(ep - e0, 0, 3))
    hq, lq = _doubled(*_mantissa_product(m[1], m[2]), jnp.clip(eq - e0, 0, 3))
    low = sp * lp - sq * lq
    # arithmetic shift: low = (low >> 52) 2^52 + (low & _LOW52)
    high = sp * hp - sq * hq + (low >> 52)
    all_exact = exact[0] & exact[1] & exact[2] & exact[3]
    return near, high, low & _LOW52, e0, sp, sq, ep, eq, all_exact


def _det2_sign_float64(ux, uy, vx, vy):
    """Exact sign of ``ux vy - uy vx`` in float64 (:func:`_integer_difference`): the sign of
    ``high 2^52 + low`` where the products are near, else of the larger product."""
    near, high, low, _, sp, sq, ep, eq, exact = _integer_difference(ux, uy, vx, vy)
    s_near = jnp.where(high != 0, jnp.sign(high), jnp.sign(low))
    s_far = jnp.where(sq == 0, sp, jnp.where((sp == 0) | (eq > ep), -sq, sp))
    d = jnp.where(near, s_near, s_far)
    return jnp.where(exact, d, UNKNOWN).astype(CODE)


#: rounding count of :func:`det2_accurate` (relative error at most ``gamma_3``)
DET2_ROUNDINGS = 3


def det2_accurate(ux, uy, vx, vy):
    """``ux vy - uy vx`` in float64 with a relative error of at most ``gamma_3``
    (:data:`DET2_ROUNDINGS`), also where the difference cancels; NaN where that is not proven (an
    input not a normal number or zero, a product or the result below the normal range).

    Near products (:func:`_integer_difference`): ``fl(fl(high) 2^52 + low) 2^e0``, exact for
    ``high`` in {-1, 0, 1} and within ``gamma_3`` otherwise (``|V| >= |high| 2^51`` then).
    Otherwise (``|q| < |p| / 4`` or the reverse, or a product zero) the float difference, within
    ``gamma_3`` with or without a fused multiply-add.  Any copy of the result is within the bound,
    so a compiler's recomputation cannot break the certificates that use it.
    """
    near, high, low, e0, sp, sq, _, _, exact = _integer_difference(ux, uy, vx, vy)
    v = high.astype(jnp.float64) * 2.0**52 + low.astype(jnp.float64)
    aligned = jnp.ldexp(v, e0.astype(jnp.int32))
    fp, fq = ux * vy, uy * vx
    tiny = float(jnp.finfo(jnp.float64).tiny)
    # the float path's bound needs each product exactly zero (a zero input, not an underflow) or
    # far above the normal range
    floor = tiny * 2.0**60
    far_ok = ((sp == 0) | (jnp.abs(fp) >= floor)) & ((sq == 0) | (jnp.abs(fq) >= floor))
    far = fp - fq
    far_ok = far_ok & ((far == 0) | (jnp.abs(far) >= tiny))
    near_ok = (v == 0) | (jnp.abs(aligned) >= tiny)  # an exact zero, or no underflow in ldexp
    d = jnp.where(near, aligned, far)
    ok = exact & jnp.isfinite(d) & jnp.where(near, near_ok, far_ok)
    return jnp.where(ok, d, jnp.nan)


def has_float64() -> bool:
    """Whether JAX computes in float64 here (``jax_enable_x64``): float32 inputs can then be
    evaluated exactly converted, with the float64 error model."""
    return jnp.zeros((), jnp.float64).dtype == jnp.float64


def _magnitude_bits(x):
    """The bits of ``x`` without its sign bit, as an integer of the same width."""
    x = jnp.asarray(x)
    itype = {4: jnp.int32, 8: jnp.int64}[jnp.dtype(x.dtype).itemsize]
    return jax.lax.bitcast_convert_type(x, itype) & jnp.iinfo(itype).max


def _magnitude(x):
    """``|x|``'s bits as a float integer (exact below ``2^nmant``, i.e. for every subnormal)."""
    return _magnitude_bits(x).astype(jnp.float64 if has_float64() else jnp.float32)


def nonzero(x):
    """``x != 0`` read from the bits.  XLA on CPU runs every program (jitted or not) with
    denormals-are-zero and flush-to-zero set, so there a subnormal ``x`` compares equal to zero
    and every arithmetic operation reads it as zero; its bits do not.  LLVM, which assumes IEEE
    subnormals, folds an integer test ``bits & ~sign == 0`` back into ``x == 0.0``: the magnitude
    bits are tested as a float sum instead (``m + 0.5 > 1`` for the integer ``m``), which no
    optimization without fast-math flags rewrites."""
    return _magnitude(x) + 0.5 > 1


def subnormal(x):
    """``True`` where ``x`` is subnormal (nonzero, below the smallest normal number), from the
    bits (:func:`nonzero`)."""
    m = _magnitude(x)
    return (m + 0.5 > 1) & (m < 2 ** jnp.finfo(jnp.asarray(x).dtype).nmant)


def sign_of(x):
    """Exact sign code of a floating-point number (:data:`CODE`); a subnormal's from its bits
    (:func:`nonzero`)."""
    x = jnp.asarray(x)
    tiny_sign = jnp.where(jnp.signbit(x), -1, 1)
    return jnp.where(subnormal(x), tiny_sign, jnp.sign(x)).astype(CODE)


def known(s):
    return s != UNKNOWN
