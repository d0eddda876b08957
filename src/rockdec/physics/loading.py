"""The random streams of a series: its load, discrete white noise as velocity impulses (paper
§4), and the noise of the sensor that records its angle; one pair of streams per seed.

Every simulator (simplified, Housner, fixed step) draws its impulses here
(:func:`draw_impulses`), so one seed means one load whatever the model: white, low-pass
(``p_n = c p_{n-1} + sqrt(1 - c^2) w_n``, corner ``f_c = -ln(c)/(2 pi dt)``, the open question
of paper §6; :func:`low_pass`) or of a given spectrum (:class:`ImpulseSpectrum`, by circulant
embedding of :func:`embedding_size` ``M`` samples with the gains :func:`spectral_gain`
``sqrt(S(k/M))``). The streams are NumPy's (``SeedSequence(seed)``, PCG64,
:func:`series_rng`, :func:`sensor_rng`); the compiled kernels (:func:`draw_series`,
:func:`add_sensor_noise`) draw the same numbers bit for bit (:func:`stream_words`, PCG64
and its ziggurat in LLVM), so a block of series is drawn and integrated without Python
between series.

Explanation: docs/explanation/method/simulation.md (§3.1 Loading).
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numba
import numpy as np
from llvmlite import ir
from numba.core import cgutils, types
from numba.extending import intrinsic
from numba.np.random._constants import fi_double, ki_double, wi_double, ziggurat_nor_inv_r, ziggurat_nor_r

from rockdec.validate import InputError, is_whole, show

__all__ = [
    "ImpulseSpectrum", "SENSOR_STREAM", "WRAP_TOLERANCE", "add_sensor_noise", "check_load", "check_seeds",
    "draw_impulses", "draw_series", "embedding_size", "low_pass", "sensor_rng", "series_rng",
    "spectral_gain", "stream_words",
]

SENSOR_STREAM = 1
"""Spawn key of a series' sensor-noise stream (the load's stream has none), so the sensor's
noise never shares random numbers with the load."""


def series_rng(seed: int) -> np.random.Generator:
    """The random generator of one series' load: NumPy ``SeedSequence(seed)``, PCG64.

    A series depends on its own seed only, whatever other seeds, chunks or cores run
    beside it.
    """
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence(int(seed))))


def sensor_rng(seed: int) -> np.random.Generator:
    """The random generator of one series' sensor noise: ``SeedSequence(seed)`` spawned once
    (:data:`SENSOR_STREAM`), PCG64; independent of :func:`series_rng` of the same seed."""
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence(int(seed), spawn_key=(SENSOR_STREAM,))))


# NumPy's SeedSequence (numpy/random/bit_generator.pyx): pool of 4 words, its hash constants.
# Python ints: exact on a seed's Python ints, and uint64 arrays stay uint64 (the 32-bit words masked).
_POOL_SIZE = 4
_INIT_A, _MULT_A, _INIT_B, _MULT_B = 0x43B0D7E5, 0x931E8875, 0x8B51F9DD, 0x58F38DED
_MIX_MULT_L, _MIX_MULT_R = 0xCA01F9DD, 0x4973F715
_WORD = 0xFFFFFFFF
#: Up to this many seeds :func:`stream_words` hashes each seed's Python ints (a cost per
#: seed); more share NumPy's array operations (a fixed cost per call, whatever the number);
#: the two costs meet near this many seeds.
_SEEDS_ONE_BY_ONE = 16
#: PCG64's multiplier (numpy/random/src/pcg64/pcg64.h, PCG_DEFAULT_MULTIPLIER_128).
_PCG_MULTIPLIER = 0x2360ED051FC65DA44385DF649FCCF645
#: A PCG64 output's top 53 bits times this: a double in ``[0, 1)``.
_DOUBLE_UNIT = 1.0 / 9007199254740992.0


#: Seeds are whole numbers in ``[0, MAX_SEED]`` (int64, the words :func:`stream_words` splits).
MAX_SEED = 2**63 - 1


def check_seeds(seeds) -> np.ndarray:
    """``seeds`` (a whole number or a sequence of them) as a 1-d int64 array; raises
    :class:`rockdec.validate.InputError` in one sentence for a seed that is not a whole number
    (a float, a bool, text) or lies outside ``[0, MAX_SEED]``, and for a table of seeds.

    Examples
    --------
    >>> check_seeds(3), check_seeds([0, 7]).dtype
    (array([3]), dtype('int64'))
    >>> check_seeds(2**70)
    Traceback (most recent call last):
    ...
    rockdec.validate.InputError: seed 1.18e+21 is beyond 2**63 - 1; give seeds from 0 to 2**63 - 1.
    """
    array = np.atleast_1d(seeds if isinstance(seeds, np.ndarray) else np.asarray(seeds, dtype=object))
    if array.ndim != 1:
        raise InputError(f"seeds of shape {array.shape}: not one seed nor a sequence of them; give a whole number or a list of them.")
    if array.dtype.kind == "i":  # at most MAX_SEED already
        wrong = np.flatnonzero(array < 0)[:1] if array.size and array.min() < 0 else []
    elif array.dtype.kind == "u":
        wrong = np.flatnonzero(array > np.uint64(MAX_SEED))[:1]
    else:
        wrong = [i for i, seed in enumerate(array) if not (is_whole(seed) and 0 <= seed <= MAX_SEED)][:1]
    for i in wrong:
        seed = array[i].item() if isinstance(array[i], np.generic) else array[i]
        if not is_whole(seed):
            raise InputError(f"seed {show(seed)} is not a whole number; give whole seeds from 0 to 2**63 - 1.")
        if seed < 0:
            raise InputError(f"seed {show(seed)} is negative; give seeds >= 0.")
        raise InputError(f"seed {show(seed)} is beyond 2**63 - 1; give seeds from 0 to 2**63 - 1.")
    return np.asarray(array, dtype=np.int64)


def stream_words(seeds, spawn: int = -1) -> np.ndarray:
    """``SeedSequence(seed).generate_state(4, np.uint64)`` for every seed (``spawn < 0``,
    :func:`series_rng`) or for its spawn ``spawn`` (:data:`SENSOR_STREAM`: :func:`sensor_rng`):
    a ``(len(seeds), 4)`` uint64 array, the words that seed PCG64 (:func:`_normals`).

    NumPy's ``SeedSequence`` (numpy/random/bit_generator.pyx) on uint64 arrays of all the seeds
    at once, or on each seed's Python ints for a few (:data:`_SEEDS_ONE_BY_ONE`,
    :func:`_generate_state`): the seed's two 32-bit words, least significant first, padded with zeros to the
    pool of 4 (one word or two hash alike), then the spawn key's word; ``hashmix`` of each into
    the pool, each pool word and each word beyond the pool mixed into every other pool word,
    and ``generate_state``'s eight 32-bit words cycling over the pool, paired low word first.
    ``0 <= seed < 2**63``; a negative seed raises :class:`rockdec.validate.InputError`.
    """
    seeds = check_seeds(seeds)
    spawn_key = [spawn] if spawn >= 0 else []
    if seeds.size <= _SEEDS_ONE_BY_ONE:
        seeds = [int(seed) for seed in seeds]
        return np.array([_generate_state([seed & _WORD, seed >> 32, 0, 0] + spawn_key) for seed in seeds], dtype=np.uint64).reshape(-1, 4)
    seeds = seeds.astype(np.uint64)
    zero = np.zeros_like(seeds)
    return np.stack(_generate_state([seeds & _WORD, seeds >> 32, zero, zero] + [np.full_like(seeds, k) for k in spawn_key]), axis=-1)


def _generate_state(entropy: list) -> list:
    """SeedSequence's mixing of the words ``entropy`` (Python ints below 2**32, or uint64 arrays
    of them) into the pool and its ``generate_state(4, uint64)``: the four 64-bit words."""
    hash_const = _INIT_A

    def hashmix(value):
        nonlocal hash_const
        value = (value ^ hash_const) & _WORD
        hash_const = (hash_const * _MULT_A) & _WORD
        value = (value * hash_const) & _WORD
        return value ^ (value >> 16)

    def mix(x, y):
        result = (_MIX_MULT_L * x - _MIX_MULT_R * y) & _WORD
        return result ^ (result >> 16)

    pool = [hashmix(entropy[i]) for i in range(_POOL_SIZE)]
    for src in range(len(entropy)):
        for dst in range(_POOL_SIZE):
            if src != dst:
                pool[dst] = mix(pool[dst], hashmix(pool[src] if src < _POOL_SIZE else entropy[src]))
    hash_const = _INIT_B
    words = []
    for i in range(8):
        value = (pool[i % _POOL_SIZE] ^ hash_const) & _WORD
        hash_const = (hash_const * _MULT_B) & _WORD
        value = (value * hash_const) & _WORD
        words.append(value ^ (value >> 16))
    return [words[2 * k] | (words[2 * k + 1] << 32) for k in range(4)]


@intrinsic
def _normals(typingctx, words, out):
    """Fill ``out`` (float64, C-ordered) with the standard normal numbers of the PCG64 generator
    that ``words`` (uint64, C-ordered: a row of :func:`stream_words`) seeds, as NumPy's
    ``standard_normal(out=out)`` draws them, bit for bit; written in LLVM, so that numba types
    and lowers none of it (module docstring).

    PCG64's seeding (numpy/random/src/pcg64: ``pcg64_set_seed``, ``pcg_setseq_128_srandom_r``):
    seed ``words[0:2]`` and increment ``(words[2:4] << 1) | 1`` as 128-bit numbers, the state
    ``(increment + seed) * multiplier + increment``. Each output: the step ``state * multiplier
    + increment`` modulo 2**128 and the XSL-RR output, the state's halves xor-ed and rotated
    right by its top 6 bits. Per number NumPy's ``random_standard_normal``
    (numpy/random/src/distributions): an output's low byte picks one of the ziggurat's 256
    layers, its bit 8 the sign, its next 52 bits the magnitude, accepted under the layer's
    ``ki_double``; else layer 0 draws the tail (two doubles ``u`` of an output's top 53 bits each,
    ``xx = -(1/r) log1p(-u1)``, ``yy = -log1p(-u2)``, until ``2 yy > xx^2``) and another layer its
    wedge (one double, against ``exp(-x^2 / 2)``), and a rejection starts over.
    """
    if not (isinstance(words, types.Array) and words.dtype == types.uint64 and words.ndim == 1 and words.layout == "C"
            and isinstance(out, types.Array) and out.dtype == types.float64 and out.ndim == 1 and out.layout == "C"):
        return None

    def codegen(context, builder, sig, args):
        i64, wide, f64 = ir.IntType(64), ir.IntType(128), ir.DoubleType()
        module = builder.module
        word = context.make_array(sig.args[0])(context, builder, args[0])
        target = context.make_array(sig.args[1])(context, builder, args[1])
        w = [builder.load(builder.gep(word.data, [ir.Constant(i64, k)])) for k in range(4)]

        def joined(hi, lo):
            return builder.or_(builder.shl(builder.zext(hi, wide), ir.Constant(wide, 64)), builder.zext(lo, wide))

        def table(name, values, kind):
            data = ir.Constant(ir.ArrayType(kind, values.size), [ir.Constant(kind, v) for v in values.tolist()])
            return cgutils.global_constant(module, f"rockdec_ziggurat_{name}", data)

        wi, ki, fi = table("wi", wi_double, f64), table("ki", ki_double, i64), table("fi", fi_double, f64)
        log1p = cgutils.get_or_insert_function(module, ir.FunctionType(f64, [f64]), "log1p")
        exp = module.declare_intrinsic("llvm.exp", [f64])
        multiplier = ir.Constant(wide, _PCG_MULTIPLIER)
        inc = builder.or_(builder.shl(joined(w[2], w[3]), ir.Constant(wide, 1)), ir.Constant(wide, 1))
        state = cgutils.alloca_once(builder, wide)
        builder.store(builder.add(builder.mul(builder.add(inc, joined(w[0], w[1])), multiplier), inc), state)

        def output():
            now = builder.add(builder.mul(builder.load(state), multiplier), inc)
            builder.store(now, state)
            hi = builder.trunc(builder.lshr(now, ir.Constant(wide, 64)), i64)
            folded, turn = builder.xor(hi, builder.trunc(now, i64)), builder.lshr(hi, ir.Constant(i64, 58))
            left = builder.and_(builder.sub(ir.Constant(i64, 64), turn), ir.Constant(i64, 63))
            return builder.or_(builder.lshr(folded, turn), builder.shl(folded, left))

        def double():
            return builder.fmul(builder.uitofp(builder.lshr(output(), ir.Constant(i64, 11)), f64), ir.Constant(f64, _DOUBLE_UNIT))

        def entry(array, index):
            return builder.load(builder.gep(array, [ir.Constant(i64, 0), index]))

        x_var = cgutils.alloca_once(builder, f64)
        with cgutils.for_range(builder, target.nitems) as loop:
            draw, slow, tail, wedge, done = (builder.append_basic_block(n) for n in ("draw", "slow", "tail", "wedge", "done"))
            builder.branch(draw)
            builder.position_at_end(draw)
            r = output()
            idx = builder.and_(r, ir.Constant(i64, 0xFF))
            r = builder.lshr(r, ir.Constant(i64, 8))
            rabs = builder.and_(builder.lshr(r, ir.Constant(i64, 1)), ir.Constant(i64, 0x000FFFFFFFFFFFFF))
            x = builder.fmul(builder.uitofp(rabs, f64), entry(wi, idx))
            negative = builder.trunc(r, ir.IntType(1))
            x = builder.select(negative, builder.fneg(x), x)
            builder.store(x, x_var)
            builder.cbranch(builder.icmp_unsigned("<", rabs, entry(ki, idx)), done, slow)
            builder.position_at_end(slow)
            builder.cbranch(builder.icmp_unsigned("==", idx, ir.Constant(i64, 0)), tail, wedge)
            builder.position_at_end(tail)
            xx = builder.fmul(ir.Constant(f64, -ziggurat_nor_inv_r), builder.call(log1p, [builder.fneg(double())]))
            yy = builder.fneg(builder.call(log1p, [builder.fneg(double())]))
            outside = builder.fcmp_ordered(">", builder.fadd(yy, yy), builder.fmul(xx, xx))
            at = builder.fadd(ir.Constant(f64, ziggurat_nor_r), xx)
            upper = builder.trunc(builder.lshr(rabs, ir.Constant(i64, 8)), ir.IntType(1))
            builder.store(builder.select(upper, builder.fneg(at), at), x_var)
            builder.cbranch(outside, done, tail)
            builder.position_at_end(wedge)
            below = entry(fi, builder.sub(idx, ir.Constant(i64, 1)))
            level = entry(fi, idx)
            y = builder.fadd(builder.fmul(builder.fsub(below, level), double()), level)
            bound = builder.call(exp, [builder.fmul(builder.fmul(ir.Constant(f64, -0.5), x), x)])
            builder.cbranch(builder.fcmp_ordered("<", y, bound), done, draw)
            builder.position_at_end(done)
            builder.store(builder.load(x_var), builder.gep(target.data, [loop.index]))
        return context.get_dummy_value()

    return types.none(words, out), codegen


@numba.njit(nogil=True, cache=True)
def low_pass(w, pole):
    """First-order low-pass filter in place: ``w[n] <- pole w[n-1] + sqrt(1 - pole^2) w[n]``
    for ``n >= 1`` (``w[n-1]`` already filtered), ``w[0]`` kept: unit-variance white ``w``
    becomes a stationary sequence of unit variance and autocorrelation ``pole^m``."""
    gain = math.sqrt(1.0 - pole * pole)
    for n in range(1, w.size):
        w[n] = pole * w[n - 1] + gain * w[n]
    return w


class ImpulseSpectrum(NamedTuple):
    """A load spectrum as the simulators draw it: ``frequency`` in cycles per step (ascending,
    ``>= 0``) and the one-sided power spectral density ``psd`` (``>= 0``, any scale) there;
    :meth:`rockdec.physics.record_model.Load.draw_options` places a scene's table at its sampling."""

    frequency: tuple
    psd: tuple


WRAP_TOLERANCE = 1e-4
"""Largest autocorrelation the circulant embedding may wrap around (:func:`embedding_size`)."""


@functools.lru_cache(maxsize=16)
def embedding_size(spectrum: ImpulseSpectrum, n: int) -> int:
    """Length ``M`` of the periodic series whose first ``n`` samples are ``n`` impulses of
    ``spectrum``: the next fast length of ``n + L``, ``L`` the last lag up to ``n`` at which the
    autocorrelation (at ``M = 2n``) exceeds :data:`WRAP_TOLERANCE`, plus one."""
    from scipy import fft

    trial = fft.next_fast_len(2 * n, real=True)
    acf = np.abs(fft.irfft(spectral_gain(spectrum, trial) ** 2, n=trial)[: n + 1])
    lag = int(np.flatnonzero(acf > WRAP_TOLERANCE)[-1]) + 1  # acf[0] = 1
    return fft.next_fast_len(n + lag, real=True)


@functools.lru_cache(maxsize=16)
def spectral_gain(spectrum: ImpulseSpectrum, size: int) -> np.ndarray:
    """Gains ``sqrt(S(k/size))`` of the ``size // 2 + 1`` bins of a real transform of ``size``
    points (module docstring), scaled so that ``S`` averages 1 over the ``size`` bins of the circle."""
    f, s = np.asarray(spectrum.frequency, dtype=np.float64), np.asarray(spectrum.psd, dtype=np.float64)
    if not (f.size >= 2 and f.size == s.size and np.all(np.diff(f) > 0) and f[0] >= 0 and np.all(np.isfinite(s)) and s.min() >= 0
            and s.max() > 0):
        raise InputError(
            f"the load spectrum ({f.size} rows from {f[0]:.3g} to {f[-1]:.3g} cycles per step) is not a table of ascending "
            "frequencies >= 0 and PSD values >= 0, not all 0; give such a table (rockdec.physics.record_model.Load checks one)"
        )
    s = s / s.max()  # only the shape counts; no overflow in the mean below
    bins = np.arange(size // 2 + 1) / size
    power = np.zeros(bins.size)
    pos = f > 0.0
    inside = bins > 0.0
    power[inside] = np.interp(np.log(bins[inside]), np.log(f[pos]), s[pos], left=0.0, right=0.0)
    if f[0] == 0.0:
        below = bins < f[pos][0]
        power[below] = np.interp(bins[below], f[:2], s[:2])
    weights = np.full(bins.size, 2.0)
    weights[0] = 1.0
    if size % 2 == 0:
        weights[-1] = 1.0
    mean = float(np.dot(weights, power)) / size
    if not mean > 0.0:
        raise InputError(
            f"the load spectrum (rows from {f[0]:.3g} to {f[-1]:.3g} cycles per step) holds no power between 0 and the "
            "Nyquist frequency of 0.5 cycles per step of this simulation; give a table that covers the rocking band"
        )
    gain = np.sqrt(power / mean)
    gain.flags.writeable = False  # shared by every caller of the cache
    return gain


def _draw_spectrum(rng: np.random.Generator, out: np.ndarray, spectrum: ImpulseSpectrum) -> None:
    """Unit-variance impulses of ``spectrum`` into ``out`` by circulant embedding (module docstring)."""
    from scipy import fft

    size = embedding_size(spectrum, out.size)
    white = rng.standard_normal(size)
    out[:] = fft.irfft(fft.rfft(white) * spectral_gain(spectrum, size), n=size)[: out.size]


def check_load(pole: float, spectrum: ImpulseSpectrum | None = None) -> None:
    """Refuse a load pole outside ``[0, 1)`` and a load both low-pass filtered and of a spectrum."""
    if not 0.0 <= pole < 1.0:
        raise InputError(f"load pole {pole}: not in [0, 1); give the low-pass filter's pole, or draw a spectrum load with spectrum=")
    if spectrum is not None and pole > 0.0:
        raise InputError("a load is either low-pass filtered (pole) or of a given spectrum, not both; give one of them")


@numba.njit(nogil=True, cache=True, inline="always")
def draw_series(words, out, sigma_p, pole):
    """:func:`draw_impulses` of ``series_rng(seed)`` for a white (``pole`` None) or low-pass
    load, inside numba, ``words`` the seed's row of :func:`stream_words` (:func:`_normals`,
    :func:`low_pass`): the same impulses bit for bit. ``pole`` as :func:`check_load` accepts
    it; None is a type of its own to numba, which drops the filter before typing it, so a
    white load compiles no filter."""
    if sigma_p > 0.0:
        _normals(words, out)
        if pole is not None and out.size:
            low_pass(out, pole)
    for i in range(out.size):
        out[i] = out[i] * sigma_p if sigma_p > 0.0 else 0.0
    return out


def draw_impulses(rng: np.random.Generator, out: np.ndarray, sigma_p: float, pole: float = 0.0,
                  spectrum: ImpulseSpectrum | None = None) -> np.ndarray:
    """Fill ``out`` with the next impulses ``p_n ~ N(0, sigma_p^2)`` (rad/s) of ``rng``.

    ``sigma_p = 0`` gives zeros (a free response) and draws nothing. Drawing a series in
    blocks continues the same stream, so white blocks concatenate to the whole series.
    ``pole`` ``c`` in ``[0, 1)``: the low-pass filtered load of the module docstring
    (:func:`low_pass`), started stationary (``p_0 = sigma_p w_0``); ``0`` is white noise.
    ``spectrum``: impulses of that spectrum instead (:class:`ImpulseSpectrum`, circulant
    embedding of the module docstring), ``out`` being the whole series.
    """
    check_load(pole, spectrum)
    if sigma_p > 0.0:
        if spectrum is not None:
            if out.size:
                _draw_spectrum(rng, out, spectrum)
        else:
            rng.standard_normal(out=out)
            if pole > 0.0 and out.size:
                low_pass(out, pole)
        out *= sigma_p
    else:
        out[:] = 0.0
    return out


def add_sensor_noise(theta: np.ndarray, seeds, std: float) -> np.ndarray:
    """``theta(seed, time)`` (changed in place) plus white sensor noise of standard deviation
    ``std`` (rad), each row from :func:`sensor_rng` of its seed (drawn in the kernel,
    :func:`stream_words` and :func:`_normals`: the same numbers); ``std = 0`` draws nothing."""
    if std > 0.0:
        seeds = np.atleast_1d(np.asarray(seeds, dtype=np.int64))
        rows = min(len(theta), seeds.size)
        _add_sensor_noise(theta, stream_words(seeds[:rows], SENSOR_STREAM), float(std), np.empty(theta.shape[-1] if rows else 0))
    return theta


@numba.njit(nogil=True, cache=True)
def _add_sensor_noise(theta, words, std, noise):
    """:func:`add_sensor_noise`'s loop: row ``r`` of ``theta`` plus ``std`` times the normal
    numbers of ``words[r]`` (:func:`stream_words` of the sensor streams, :func:`_normals`),
    drawn into the scratch row ``noise``."""
    for r in range(words.shape[0]):
        _normals(words[r], noise)
        row = theta[r]
        for i in range(row.size):
            row[i] += std * noise[i]
