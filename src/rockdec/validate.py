"""Checks of user input at the edges (command line, config, files), shared by every entry point.

Each check returns the value it accepts, converted (``float``, ``int``, ``str``), or raises
:class:`InputError` with one sentence that names the value by the name the user wrote
(a keyword argument written in backquotes, ```dt```, which the command line shows as its flag; a config key) and says how to fix it:
``"`dt` nan: not a finite number; give a time step > 0 in s."``

NaN never passes: every comparison with NaN is false, so each range test is written as
``not (lo <= x <= hi)``, and finiteness is tested first.
"""

from __future__ import annotations

import math
import numbers
import re

__all__ = [
    "InputError", "MAX_NAME_BYTES", "SQUARE_RANGE", "file_kind", "finite", "identifier", "in_range",
    "integer", "is_finite_number", "is_number", "is_whole", "json_number", "memory", "path_name",
    "positive", "show",
]

#: A plain identifier: ASCII letter first, then letters, digits or underscores.
IDENTIFIER = re.compile(r"[A-Za-z][A-Za-z0-9_]*")


class InputError(ValueError):
    """Input a user can fix; the message names the value and the fix (exit code 2 in the CLI)."""


#: The most digits :func:`show` writes out for a whole number: 20 hold every 64-bit integer.
SHOWN_DIGITS = 20


def show(value) -> str:
    """``value`` as the user would have written it: ``nan``, ``6000.0``, ``12``, ``'a/b'``;
    a whole number of more than :data:`SHOWN_DIGITS` digits in the short form ``1.84e+19``.

    Examples
    --------
    >>> show(6000), show(6000.0), show(float("nan")), show(10**150)
    ('6000', '6000.0', 'nan', '1e+150')
    """
    if is_whole(value):
        value = int(value)
        if value.bit_length() * math.log10(2) < SHOWN_DIGITS:
            return str(value)
        return _short_whole(value)
    if is_number(value):
        return repr(float(value))
    return repr(value)


def _short_whole(value: int) -> str:
    """A whole number of any size as ``m.mme+XX`` (three significant digits), without writing
    out its digits (Python refuses ``str`` of an integer beyond 4300 digits)."""
    drop = max(value.bit_length() - 60, 0)
    exponent = math.log10(abs(value >> drop)) + drop * math.log10(2)
    power = math.floor(exponent)
    mantissa = 10 ** (exponent - power)
    if round(mantissa, 2) >= 10:
        mantissa, power = mantissa / 10, power + 1
    return f"{'-' if value < 0 else ''}{mantissa:.3g}e+{power:02d}"


def _fail(name, value, problem: str, fix: str) -> InputError:
    return InputError(f"{name} {show(value)}: {problem}; {fix}.")


def is_number(value) -> bool:
    """A real number (not a bool, not a string), finite or not."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def is_finite_number(value) -> bool:
    """A real number other than NaN and +-inf."""
    return is_number(value) and math.isfinite(value)


def is_whole(value) -> bool:
    """An integer type (Python or NumPy), not a bool and not a float that happens to be whole."""
    return isinstance(value, numbers.Integral) and not isinstance(value, bool)


def json_number(x) -> float | None:
    """``x`` as a float for a JSON document, ``None`` when it is NaN or infinite.

    Examples
    --------
    >>> json_number(0.5), json_number(float("nan"))
    (0.5, None)
    """
    x = float(x)
    return x if math.isfinite(x) else None


def finite(value, name: str, fix: str = "give a finite number") -> float:
    """``value`` as a float; refuses NaN, +-inf and anything that is not a real number."""
    if not is_number(value):
        raise _fail(name, value, "not a number", fix)
    if not math.isfinite(value):
        raise _fail(name, value, "not a finite number", fix)
    return float(value)


def in_range(value, name: str, lo=-math.inf, hi=math.inf, fix: str | None = None, *, lo_open=False, hi_open=False) -> float:
    """``value`` as a finite float in the interval from ``lo`` to ``hi`` (closed unless ``*_open``)."""
    left, right = ("(" if lo_open else "["), (")" if hi_open else "]")
    fix = fix or f"give a value in {left}{lo:g}, {hi:g}{right}"
    x = finite(value, name, fix)
    above = x > lo if lo_open else x >= lo
    below = x < hi if hi_open else x <= hi
    if not (above and below):
        if hi == math.inf:
            raise _fail(name, value, f"not {'>' if lo_open else '>='} {lo:g}", fix)
        raise _fail(name, value, f"outside {left}{lo:g}, {hi:g}{right}", fix)
    return x


def positive(value, name: str, fix: str | None = None, *, allow_zero=False) -> float:
    """``value`` as a finite float ``> 0`` (``>= 0`` with ``allow_zero``)."""
    fix = fix or f"give a finite number {'>=' if allow_zero else '>'} 0"
    return in_range(value, name, 0.0, math.inf, fix, lo_open=not allow_zero)


def integer(value, name: str, minimum: int | None = None, fix: str | None = None) -> int:
    """``value`` as an int of an integer type, at least ``minimum``.

    A float is refused even when whole (``6000.0``): in a config it is a typo for ``6000``
    that would fail later, in a rule.
    """
    fix = fix or (f"give a whole number >= {minimum}" if minimum is not None else "give a whole number")
    if not is_whole(value):
        if is_finite_number(value) and float(value).is_integer():
            raise _fail(name, value, "written as a decimal", f"write it as {int(value)}")
        raise _fail(name, value, "not a whole number", fix)
    if minimum is not None and value < minimum:
        raise _fail(name, value, f"below {minimum}", fix)
    return int(value)


def identifier(value, name: str) -> str:
    """``value`` as a plain identifier (letters, digits, ``_``; a letter first).

    Names become file and folder names (``results/<scene>/``): nothing like ``../`` or
    ``/`` may slip through.
    """
    if not (isinstance(value, str) and IDENTIFIER.fullmatch(value)):
        raise _fail(name, value, "not a plain name", "use letters, digits and _ only, starting with a letter")
    return value


#: Longest file name (one path component) most file systems accept, in bytes.
MAX_NAME_BYTES = 255


def path_name(path, what: str):
    """``path`` as a :class:`pathlib.Path`, refusing a name no file system stores (a component
    longer than :data:`MAX_NAME_BYTES` bytes, or a NUL byte) before anything touches it."""
    import os
    from pathlib import Path

    text = os.fspath(path)
    if "\0" in text:
        raise InputError(f"{what} {text!r}: holds a NUL byte, which no file name can; give a plain path.")
    for part in Path(text).parts:
        if len(os.fsencode(part)) > MAX_NAME_BYTES:
            raise InputError(
                f"{what} '{part[:40]}...': a name of {len(os.fsencode(part))} bytes, longer than the "
                f"{MAX_NAME_BYTES} a file system stores; give a shorter name."
            )
    return Path(text)


#: The range of magnitudes whose squares are normal floats (neither 0 nor inf): scales the
#: simulation and the analysis square (g, sigma_p, a step, an angle's amplitude) must lie in it.
SQUARE_RANGE = (math.sqrt(2.2250738585072014e-308), math.sqrt(1.7976931348623157e308))


def file_kind(path) -> str | None:
    """What ``path`` is when it exists and is not a regular file (``"a FIFO (named pipe)"``,
    ``"a folder"``, ...), else ``None``; found by ``stat``, which never blocks, so a FIFO is
    named before an ``open()`` would wait for a writer.

    Examples
    --------
    >>> import os, tempfile
    >>> folder = tempfile.mkdtemp()
    >>> file_kind(folder), file_kind(os.path.join(folder, "none"))
    ('a folder', None)
    >>> os.mkfifo(os.path.join(folder, "pipe")); file_kind(os.path.join(folder, "pipe"))
    'a FIFO (named pipe)'
    """
    import os
    import stat

    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError):
        return None
    for test, name in ((stat.S_ISREG, None), (stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
                       (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return name
    return "not a regular file"


def available_memory() -> int:
    """Bytes of memory the machine can give this process now (``psutil``)."""
    import psutil

    return int(psutil.virtual_memory().available)


def memory(nbytes: float, what: str, fix: str) -> None:
    """Refuse a request that needs more than the available memory, before any work.

    ``what`` names the request by the values the user wrote (``"`burn_in` 400000000"``).
    """
    available = available_memory()
    if not nbytes <= available:
        raise InputError(
            f"{what} needs {nbytes / 2**30:.3g} GiB of memory, more than the {available / 2**30:.3g} GiB "
            f"this machine has free; {fix}."
        )
