"""Measured records: read a rocking record from CSV, NetCDF or ``.npy``, and check it.

A record is one uniformly sampled series of the rocking angle (rad). Everything a user's
file can get wrong is refused here with one sentence that names the file, the problem and
the fix (:class:`RecordError`): a missing, empty or unreadable file, non-numeric cells,
an unknown column or variable, a time axis that is not uniform and increasing, infinite
values, too many NaN, a constant record, or too few samples. NaN samples (gaps) are kept:
the signatures skip every segment that holds one, and the count is reported.
"""

from __future__ import annotations

import hashlib
import warnings
from pathlib import Path
from typing import NamedTuple

import numpy as np

from rockdec import timeaxis
from rockdec.timeaxis import RecordError, angle_factor, time_factor
from rockdec.validate import SQUARE_RANGE, file_kind, path_name, show

__all__ = [
    "HOLD_SHARE", "MIN_SAMPLES", "Record", "RecordError", "angle_factor", "check_values", "distinct",
    "held", "read_base", "read_records", "record_size", "same_step", "sampling_step", "time_factor",
]

#: Largest fraction of NaN samples a record may hold.
MAX_NAN_FRACTION = 0.1

#: Fewest samples a record must have (a few rocking cycles at the sampling the fits need).
MIN_SAMPLES = 1000

#: Bytes read from the start of a CSV file to sniff its separator and its line length.
SNIFF_BYTES = 1 << 16

#: CSV separators recognised in the header line, by preference.
SEPARATORS = (",", ";", "\t")

class Record(NamedTuple):
    """One record: ``theta`` (rad, 1-D, float64, NaN for gaps), ``dt`` (s), ``source`` (the file)."""

    theta: np.ndarray
    dt: float
    source: str


def sampling_step(time, source: str) -> float:
    """The step of a record's time axis (s): :func:`rockdec.timeaxis.sampling_step` with the
    fewest samples a record needs (:data:`MIN_SAMPLES`)."""
    return timeaxis.sampling_step(time, source, MIN_SAMPLES)


def _step_from_options(dt, fs, source: str) -> float | None:
    if dt is not None and fs is not None:
        raise RecordError(f"{source}: give the sampling as `dt` or `fs`, not both.")
    if fs is not None:
        if not (np.isfinite(fs) and fs > 0 and np.isfinite(1.0 / fs) and 1.0 / fs > 0):
            raise RecordError(f"`fs` {show(fs)}: not a positive, finite sampling rate with a finite step 1/fs; give the rate in Hz, > 0.")
        return 1.0 / fs
    if dt is not None and not (np.isfinite(dt) and dt > 0):
        raise RecordError(f"`dt` {show(dt)}: not a positive, finite number of seconds; give the sampling step in s, > 0.")
    return dt


def _sniff_csv(path: Path) -> tuple[str, float]:
    """The separator of a CSV file (``","`` for one column, ``r"\\s+"`` for spaces) and its
    mean bytes per line, from its first :data:`SNIFF_BYTES` bytes; refuses a binary file."""
    with open(path, "rb") as f:
        head = f.read(SNIFF_BYTES)
    if b"\0" in head:
        raise RecordError(f"{path}: holds NUL bytes in its first {len(head)} bytes, so it is a binary file, not a text CSV; give a CSV of numbers, a .nc or a .npy file.")
    lines = head.count(b"\n") + (len(head) < SNIFF_BYTES and not head.endswith(b"\n"))
    if lines == 0:
        raise RecordError(f"{path}: its first {len(head)} bytes hold no line break, so it is not a CSV of one sample per line; give one sample per line.")
    header = next((line for line in head.decode("utf-8", "replace").splitlines() if line.strip() and not line.lstrip().startswith("#")), "")
    counts = {sep: header.count(sep) for sep in SEPARATORS}
    best = max(counts, key=counts.get)
    if counts[best]:
        return best, len(head) / lines
    return (r"\s+" if len(header.split()) > 1 else ","), len(head) / lines


def _plain_columns(path: Path, sep: str, column: str) -> dict[str, np.ndarray] | None:
    """The columns of a plain CSV file by name, read by NumPy (pandas is slow to import):
    a first line (after comments) of distinct names, ``column`` among them, and on every
    other line a finite number under each. ``None`` for any other file, which pandas reads
    (:func:`_read_csv`, with its messages for what is wrong)."""
    try:
        with open(path, encoding="utf-8-sig") as f:  # a byte-order mark is not part of the first name
            header = next((line for line in f if line.strip() and not line.lstrip().startswith("#")), "")
            names = [n.strip() for n in (header.split() if sep == r"\s+" else header.split(sep))]
            if column not in names or "" in names or len(set(names)) < len(names):
                return None
            with warnings.catch_warnings():  # a file of a header alone: pandas names it
                warnings.simplefilter("ignore", UserWarning)
                values = np.loadtxt(f, delimiter=None if sep == r"\s+" else sep, comments="#", ndmin=2, dtype=np.float64)
    except (ValueError, UnicodeDecodeError):
        return None
    if values.shape[1] != len(names) or not values.size or not np.isfinite(values).all():
        return None
    return dict(zip(names, np.ascontiguousarray(values.T)))  # each column's samples side by side, as the kernels read them


def _read_csv(path: Path, column: str, step: float | None) -> tuple[np.ndarray, float]:
    sep, _ = _sniff_csv(path)
    plain = _plain_columns(path, sep, column)
    values, time = (plain[column], plain.get("time")) if plain is not None else _pandas_columns(path, sep, column)
    if time is not None:
        if step is not None:
            raise RecordError(f"{path}: the file has a time column, so `dt`/`fs` would contradict it; drop the option.")
        step = sampling_step(time if isinstance(time, np.ndarray) else _numeric(time, path, "time"), str(path))
    elif step is None:
        raise RecordError(f"{path}: no 'time' column; give the sampling step as `dt` (s) or `fs` (Hz).")
    return values, step


def _pandas_columns(path: Path, sep: str, column: str):
    """Column ``column`` of any CSV file pandas reads, as numbers, and its ``time`` column as
    read (``None`` when it has none); one sentence for what makes it unreadable."""
    import pandas as pd

    options = {"comment": "#", "sep": sep, "skipinitialspace": sep != r"\s+", "encoding": "utf-8-sig"}
    try:
        table = pd.read_csv(path, **options)
    except pd.errors.EmptyDataError:
        raise RecordError(f"{path}: the file is empty; give a CSV with a 'time,{column}' header or one column and `dt`.") from None
    except (pd.errors.ParserError, UnicodeDecodeError) as exc:
        raise RecordError(f"{path}: not a readable CSV file ({str(exc).splitlines()[0]}).") from None
    if table.shape[1] == 1 and table.columns[0] not in ("time", column):
        # one headerless column: the header line is the first value
        table = pd.read_csv(path, header=None, names=[column], **options)
    table.columns = [str(c).strip() for c in table.columns]
    if column not in table.columns:
        raise RecordError(f"{path}: no column '{column}' (columns: {', '.join(table.columns)}); name it with `column`.")
    return _numeric(table[column], path, column), table["time"] if "time" in table.columns else None


def _numeric(series, path: Path, column: str) -> np.ndarray:
    import pandas as pd

    values = pd.to_numeric(series, errors="coerce").to_numpy(dtype=np.float64)
    nan_rows = np.flatnonzero(np.isnan(values))  # blank, "nan" or text: only these cells are read as text
    cells = series.iloc[nan_rows]
    bad = nan_rows[cells.notna().to_numpy() & ~cells.astype(str).str.strip().str.lower().isin(["nan", ""]).to_numpy()]
    if bad.size:
        row = int(bad[0])
        raise RecordError(f"{path}: column '{column}' row {row + 1} holds '{series.iloc[row]}', not a number; fix or blank that cell.")
    return values


def _read_netcdf(path: Path, variable: str, step: float | None, angle: bool = True) -> tuple[np.ndarray, float, str | None]:
    """The values of ``variable`` (in rad when ``angle``, else as stored), their step and
    their ``units`` attribute."""
    import xarray as xr

    try:  # times as stored, scaled by their units below (``units`` as a CF time unit, with or without "since")
        ds = xr.open_dataset(path, decode_times=False, decode_timedelta=False)
    except (OSError, ValueError) as exc:
        raise RecordError(f"{path}: not a readable NetCDF file ({exc}).") from None
    with ds:
        if variable not in ds:
            raise RecordError(f"{path}: no variable '{variable}' (variables: {', '.join(map(str, ds.data_vars))}); name it with `variable`.")
        var = ds[variable]
        if var.ndim == 2 and "time" in var.dims:
            var = var.transpose(..., "time")  # one record per row, e.g. theta(seed, time) of `rockdec simulate`
        elif var.ndim != 1:
            raise RecordError(f"{path}: variable '{variable}' has dimensions {var.dims}; give theta(time) or theta(seed, time).")
        units = var.attrs.get("units")
        values = var.values.astype(np.float64) * (angle_factor(units, str(path), variable) if angle else 1.0)
        dim = var.dims[-1]
        if step is None:
            if dim in ds.coords:
                coord = ds[dim]
                step = sampling_step(coord.values, str(path)) * time_factor(coord.attrs.get("units"), str(path), dim)
            elif "dt" in var.attrs or "dt" in ds.attrs:
                text = var.attrs.get("dt", ds.attrs.get("dt"))
                try:
                    (step,) = np.asarray(text, dtype=np.float64).ravel()
                except (TypeError, ValueError):
                    raise RecordError(f"{path}: its attribute dt {text!r} is not a number of seconds; fix it or give `dt` (s).") from None
            else:
                raise RecordError(f"{path}: '{variable}' has no time coordinate and no 'dt' attribute; give `dt` (s) or `fs` (Hz).")
    return values, step, None if units is None else str(units)


#: The first bytes of a ``.npy`` file (:mod:`numpy.lib.format`) and of a zip archive (``.npz``).
NPY_MAGIC, ZIP_MAGIC = b"\x93NUMPY", b"PK\x03\x04"


def _check_npy(path: Path) -> None:
    """Refuse a ``.npy`` file that is not one: a ``.npz`` archive (a zip) or another format,
    named by its first bytes before NumPy reads it."""
    with open(path, "rb") as f:
        head = f.read(len(NPY_MAGIC))
    if head.startswith(ZIP_MAGIC):
        raise RecordError(
            f"{path}: a .npz archive (zip) named .npy; save the record's array alone with numpy.save, or give a .csv or .nc file."
        )
    if head != NPY_MAGIC:
        raise RecordError(f"{path}: does not start as a .npy file does; save the record with numpy.save, or give a .csv or .nc file.")


def check_regular(path: Path) -> None:
    """Refuse a record path that exists but is not a regular file (a folder, a FIFO, a
    device), found without opening it: an ``open()`` of a FIFO waits for a writer."""
    kind = file_kind(path)
    if kind == "a folder":
        raise RecordError(f"{path}: a folder, not a record file; give the file.")
    if kind is not None:
        raise RecordError(f"{path}: {kind}, not a regular file; save the record to a file and give that.")


def read_records(path, *, column: str = "theta", variable: str = "theta", dt: float | None = None, fs: float | None = None,
                 checked: bool = True) -> list[Record]:
    """Read and check the records of one file (``checked=False``: read only, the checks of
    :func:`check_values` left to the analysis that takes them).

    ``.csv``/``.txt``: a header with ``time`` and ``column`` (default ``theta``), or one
    column of angles with ``dt``/``fs``; ``.nc``: ``variable`` as ``(time)`` or, one record
    per row, ``(seed, time)``, sampled by its time coordinate, a ``dt`` attribute or
    ``dt``/``fs``; ``.npy``: a 1-D array with ``dt``/``fs``. Angles in rad, times in s.
    Raises :class:`RecordError`.
    """
    source = str(path_name(path, "record"))
    values, step, _ = _read_file(path, column, variable, dt, fs, angle=True)
    rows = [(row, f"{source}[{i}]") for i, row in enumerate(values)] if values.ndim == 2 else [(values, source)]
    if checked:
        return [check_values(row, step, name) for row, name in rows]
    return [Record(np.asarray(row, dtype=np.float64), check_step(step, np.size(row), name), name) for row, name in rows]


def read_base(path, *, column: str = "base", variable: str = "base", dt: float | None = None,
              fs: float | None = None) -> tuple[list[Record], str | None]:
    """Read the base acceleration of a shake-table test from one file, in the formats of
    :func:`read_records` (values as stored, not angles), and its NetCDF ``units`` attribute
    (``None`` in the other formats). Raises :class:`RecordError`."""
    source = str(path_name(path, "base record"))
    values, step, units = _read_file(path, column, variable, dt, fs, angle=False)
    rows = [(row, f"{source}[{i}]") for i, row in enumerate(values)] if values.ndim == 2 else [(values, source)]
    return [Record(np.asarray(row, dtype=np.float64), check_step(step, np.size(row), name), name) for row, name in rows], units


def _read_file(path, column: str, variable: str, dt: float | None, fs: float | None, angle: bool) -> tuple[np.ndarray, float, str | None]:
    """The values of one record file (angles in rad when ``angle``), their step and units
    attribute (:func:`read_records`)."""
    path = path_name(path, "record")
    step = _step_from_options(dt, fs, str(path))
    check_regular(path)
    if not path.is_file():
        raise RecordError(f"{path}: no such file; check the path.")
    if path.stat().st_size == 0:
        raise RecordError(f"{path}: the file is empty; give a record with at least {MIN_SAMPLES} samples.")
    suffix = path.suffix.lower()
    units = None
    if suffix in (".csv", ".txt"):
        values, step = _read_csv(path, column, step)
    elif suffix in (".nc", ".nc4", ".netcdf"):
        values, step, units = _read_netcdf(path, variable, step, angle)
    elif suffix == ".mat":
        from rockdec.record.matlab import read_mat

        values, step = read_mat(path, variable, step)
        if step is None:
            raise RecordError(f"{path}: the .mat file has no time vector (time or t) and no dt or fs; give `dt` (s) or `fs` (Hz).")
    elif suffix == ".npy":
        _check_npy(path)
        try:
            values = np.load(path, allow_pickle=False)
        except (OSError, ValueError) as exc:
            raise RecordError(f"{path}: not a readable .npy file ({exc}).") from None
        if values.ndim != 1 or values.dtype.kind not in "fiu":
            raise RecordError(f"{path}: holds a {values.dtype} array of shape {values.shape}; give a 1-D array of numbers.")
        if step is None:
            raise RecordError(f"{path}: a .npy record has no time axis; give `dt` (s) or `fs` (Hz).")
        values = values.astype(np.float64)
    else:
        raise RecordError(f"{path}: unknown record format '{suffix}'; give a .csv, .nc, .npy or .mat file.")
    return values, step, units


def check_step(dt: float, samples: int, source: str) -> float:
    """The sampling step ``dt`` (s) of a record of ``samples``, refused when it is not a
    positive finite number or its time axis would leave the range of a float."""
    if not (np.isfinite(dt) and dt > 0):
        raise RecordError(f"{source}: the sampling step {dt} is not a positive, finite number of seconds; give `dt` in s.")
    if not np.isfinite(dt * samples) or dt < np.finfo(np.float64).tiny:
        raise RecordError(
            f"{source}: a sampling step of {dt:g} s over {samples} samples is beyond the range of a float "
            "(the record's length or its rocking period would be 0 or inf); give the step in s."
        )
    return float(dt)


def check_values(theta, dt: float, source: str) -> Record:
    """Check the samples of a record (finite step, no inf, few NaN, not constant, long enough)."""
    theta = np.asarray(theta, dtype=np.float64)
    check_step(dt, theta.size, source)
    if theta.size < MIN_SAMPLES:
        raise RecordError(f"{source}: the record has {theta.size} samples; the signatures need at least {MIN_SAMPLES} (many rocking cycles).")
    if np.any(np.isinf(theta)):
        row = int(np.flatnonzero(np.isinf(theta))[0])
        raise RecordError(f"{source}: sample {row} is infinite; remove it or mark it as a gap (NaN).")
    nan = int(np.count_nonzero(np.isnan(theta)))
    if nan > MAX_NAN_FRACTION * theta.size:
        raise RecordError(
            f"{source}: {nan} of {theta.size} samples are NaN (more than {MAX_NAN_FRACTION:.0%}); give a record with fewer gaps."
        )
    finite = theta[np.isfinite(theta)]
    if finite.size == 0 or np.ptp(finite) == 0:
        raise RecordError(f"{source}: the record is constant ({finite[0] if finite.size else 'all NaN'}); a rocking record must move.")
    peak = float(np.max(np.abs(finite)))
    if not SQUARE_RANGE[0] <= peak <= SQUARE_RANGE[1]:
        raise RecordError(
            f"{source}: the record's largest angle is {peak:.3g} rad, outside [{SQUARE_RANGE[0]:.2g}, {SQUARE_RANGE[1]:.2g}] rad, "
            "where its squares stay finite, nonzero floats; give the angles in rad (or rescale them)."
        )
    return Record(theta, float(dt), source)


#: A record holds each value for ``h`` samples (a logger's zero-order hold between its true
#: samples) when, for some ``h`` from 2 to ``MAX_HOLD``, the first differences at ``h - 1`` of
#: the ``h`` phases are exactly 0 on at least ``HOLD_SHARE`` of their samples and at the last
#: phase (across holds) on at most ``HOLD_OTHER`` (:func:`held`). A record quantised to integer
#: counts has zero differences alike at every phase: up to 0.78 of them at a resolution of a
#: fifth of ``sigma_Y`` (``e`` 0.6-0.95, 10-75 samples per cycle), the phases' shares within
#: 0.03 of each other. On 960 records (those cells, 1,000 and 20,000 samples, the project's
#: simulator and the independent one of the tests) none fired, as given or quantised to a
#: resolution of ``sigma_Y`` / 200, / 20, / 5 or / 2; holds of 2, 3 and 4 samples were all
#: found down to ``sigma_Y`` / 20, all but 3 of 2,880 at ``sigma_Y`` / 5
#: (``benchmarks/quantised_records.py``).
MAX_HOLD, HOLD_SHARE, HOLD_OTHER = 16, 0.95, 0.75


def held(record: Record) -> str | None:
    """Why a record is refused for holding each value for several samples (:data:`HOLD_SHARE`;
    the longest such hold), in one sentence naming the hold and the rate to give; else ``None``.

    Examples
    --------
    >>> y = np.sin(np.arange(4000) / 7.0)
    >>> y[1::2] = y[0::2]
    >>> print(held(Record(y, 0.01, "a.csv")))
    a.csv: the record repeats every 2nd sample (each value held for 2 samples: 100.0% of the differences within a hold are exactly 0, 0.0% of those across holds; a logger holding its value): give it at the rate it was truly sampled (every 2nd sample from sample 0, a step of 0.02 s).
    >>> held(Record(np.round(np.sin(np.arange(4000) / 7.0) * 100), 0.01, "counts.csv")) is None
    True
    """
    d = np.diff(record.theta)
    valid = np.isfinite(d)
    zero = (d == 0.0).astype(np.float64)
    k = np.arange(d.size)
    found = None
    for h in range(2, MAX_HOLD + 1):
        counts = np.bincount(k[valid] % h, minlength=h)
        if counts.min() == 0:
            break
        shares = np.bincount(k % h, weights=zero, minlength=h) / counts
        across = int(np.argmin(shares))
        within = np.delete(shares, across)
        if within.min() >= HOLD_SHARE and shares[across] <= HOLD_OTHER:
            found = h, (across + 1) % h, float(within.mean()), float(shares[across])
    if found is None:
        return None
    h, start, within, across = found
    nth = f"{h}{'nd' if h == 2 else 'rd' if h == 3 else 'th'}"
    return (
        f"{record.source}: the record repeats every {nth} sample (each value held for {h} samples: {within:.1%} of the "
        f"differences within a hold are exactly 0, {across:.1%} of those across holds; a logger holding its value): give it "
        f"at the rate it was truly sampled (every {nth} sample from sample {start}, a step of {h * record.dt:.6g} s)."
    )


def record_size(path, variable: str = "theta") -> int:
    """Samples a record file holds, read from its header (``.npy``, ``.nc``) or estimated
    from its size and first lines (``.csv``), without reading the samples; 0 when the file
    cannot tell (it is then refused when read)."""
    path = Path(path)
    if file_kind(path) is not None:
        return 0  # not a regular file: refused when read, without opening it here
    try:
        suffix = path.suffix.lower()
        if suffix in (".csv", ".txt"):
            _, line_bytes = _sniff_csv(path)
            return int(path.stat().st_size / line_bytes) if line_bytes else 0
        if suffix == ".npy":
            _check_npy(path)
            return int(np.load(path, mmap_mode="r", allow_pickle=False).size)  # the header only
        if suffix in (".nc", ".nc4", ".netcdf"):
            import xarray as xr

            with xr.open_dataset(path, decode_times=False, decode_timedelta=False) as ds:
                return int(ds[variable].size) if variable in ds else 0
    except (OSError, ValueError, KeyError):  # RecordError included: refused when read
        return 0
    return 0


def distinct(records: list[Record]) -> list[Record]:
    """``records``, refusing a record given twice (the same file, or identical samples):
    a copy would count its triggers twice and narrow the interval for nothing."""
    seen: dict[bytes, str] = {}
    for r in records:
        digest = hashlib.sha256(np.ascontiguousarray(r.theta).tobytes()).digest()
        if digest in seen:
            raise RecordError(
                f"{r.source} holds the same samples as {seen[digest]}; give each record once "
                "(a copy counts its triggers twice and makes the interval narrower than the data allow)."
            )
        seen[digest] = r.source
    return records


def same_step(records: list[Record]) -> float:
    """The common step of several records of one block; refuses steps that differ."""
    steps = np.array([r.dt for r in records])
    if np.any(np.abs(steps - steps[0]) > 1e-6 * steps[0]):
        listing = ", ".join(f"{r.source}: {r.dt:g} s" for r in records)
        raise RecordError(f"records pooled together must share one sampling step ({listing}); resample them to one step.")
    return float(steps[0])
