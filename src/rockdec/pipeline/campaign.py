"""A test campaign through the workflow: a sheet of measured records in, estimates out.

The sheet (``config/records.tsv``, its path set by the config's ``campaign.sheet``) lists one
record a row: its id, its file, its block, and the options ``rockdec estimate`` takes for it
(the columns and their defaults: ``records_schema.yaml`` beside this package, linked from
``workflow/schemas/records.schema.yaml``). :func:`read_sheet` checks every row before any job
runs, the files' time axes included, and refuses a bad row in one sentence that names the
row and the column (:class:`SheetError`).

What each job of ``workflow/rules/campaign.smk`` runs:

* :func:`simulate_step`: a record of known ``e`` for the demonstration (a row with ``simulate``);
* :func:`plan_step`: the calibrations a record's (or a block's pooled) estimate reads, found
  by running that estimate up to each calibration it asks for (:func:`plan`: the first plan
  finds the records' as given, the plan on it, once built, the high-passed records' when the
  repair decides on the high-pass), so each calibration is a job of its own keyed by its
  content (:func:`rockdec.calibrate.calibration.settings_hash`);
* :func:`calibration_step`: that calibration, into the cache ``rockdec estimate`` reads;
* :func:`estimate_step`: the estimate of a record or of a block through :func:`estimate`,
  the one adapter to the public estimate (its JSON is what ``rockdec estimate --json``
  prints for the same files and options);
* :func:`table_step`: every record's and block's estimate side by side (:func:`table`).

The steps run inside the Snakemake process (:func:`rockdec.pipeline.in_snakemake.campaign`).

A row whose ``test`` is ``free`` (a free-rocking test) goes to :func:`free_rocking_unit`
(``rockdec.free_rocking``, as ``rockdec estimate --test free`` runs it), one whose ``test`` is
``shake`` (a shake-table test, with its ``base`` record) to :func:`shake_unit`
(``rockdec.shake_table``, as ``rockdec estimate --test shake`` runs it): no calibration.
"""

from __future__ import annotations

import csv
import functools
import json
import math
import os
from importlib import resources
from pathlib import Path

import numpy as np

from rockdec import locks, timeaxis
from rockdec.free import no_record_model
from rockdec.validate import InputError

__all__ = [
    "COMPARED", "FREE_UNAVAILABLE", "MAX_ID", "MAX_SIMULATED_POINTS", "SheetError", "build_calibration", "comparison",
    "declared", "estimate_step", "estimate_unit", "file_step", "markdown", "options", "plan", "plan_step",
    "read", "read_sheet", "shake_unit", "simulate_step", "simulated_record", "simulation", "summary_dataset", "table",
    "table_step", "unit_dataset", "units",
]

#: The sheet's JSON Schema, a data file of the package: its properties are the sheet's columns.
SCHEMA_FILE = "records_schema.yaml"

#: Relative tolerance on a step the sheet gives against the file's own time axis, and between
#: the records of one block (as :func:`rockdec.record.records.same_step` pools them).
STEP_RTOL = 1e-6

#: Lines of a CSV file :func:`file_step` reads to find its step (its first rows: the check
#: before any job reads headers, never whole records).
STEP_LINES = 2000

#: Characters a record's or a block's id may have at most: its estimate's files and logs are
#: named by it (``first_plan_block_<id>-free.log``), within the 255 bytes of a file name.
MAX_ID = 64

#: Samples a record the workflow simulates (``simulate``) may have at most: the longest
#: records whose interval's coverage was measured,
#: :data:`rockdec.estimation.LONG_RATIO` times the calibration's longest simulated
#: records (:data:`rockdec.calibrate.calibration.LENGTH_CAP`); a longer one takes minutes to
#: analyse, and its estimate is warned that its coverage was not measured.
MAX_SIMULATED_POINTS = 20_000_000

#: Separators a sheet's header is not split by, which a sheet written by a spreadsheet or by
#: hand may hold instead of tabs, in words.
OTHER_SEPARATORS = {",": "commas", ";": "semicolons", " ": "spaces"}

#: Options the records of one block must share: their pooled estimate takes one of each.
BLOCK_OPTIONS = ("load", "sensor_noise", "sensor_filter", "model", "theta_cr", "g", "share_lengths", "base_units")

#: What the table says of a free-rocking row while rockdec has no free-rocking analysis.
FREE_UNAVAILABLE = "free-rocking analysis not available"


class SheetError(InputError):
    """A campaign sheet the user can fix; the message names the row and the column."""


@functools.lru_cache(maxsize=1)
def schema() -> dict:
    """The sheet's JSON Schema (``records_schema.yaml``), parsed once a process."""
    import yaml

    return yaml.safe_load(resources.files("rockdec").joinpath(SCHEMA_FILE).read_text())


def _where(sheet: Path, row: int | None, record: str | None, column: str | None) -> str:
    text = f"records sheet '{sheet}'"
    if row is not None:
        text += f", row {row}" + (f" (record '{record}')" if record else "")
    if column is not None:
        text += f", column '{column}'"
    return text


def _fail(sheet: Path, row: int | None, record: str | None, column: str | None, problem: str) -> SheetError:
    return SheetError(f"{_where(sheet, row, record, column)}: {problem}.")


def _allowed(prop: dict) -> str:
    """What a column accepts, in words."""
    if "enum" in prop:
        return "give one of " + ", ".join(map(str, prop["enum"]))
    if "pattern" in prop and prop.get("type") == "string":
        return prop["description"].split(":", 1)[-1].strip() if ":" in prop["description"] else prop["description"]
    bounds = [f"{sign} {prop[key]:g}" for key, sign in (("minimum", ">="), ("exclusiveMinimum", ">"), ("maximum", "<="),
                                                       ("exclusiveMaximum", "<")) if key in prop]
    return "give a finite number" + (" " + " and ".join(bounds) if bounds else "")


def _typed(text: str, prop: dict, fail) -> object:
    """The cell ``text`` as the schema's type of its column (a number for ``number``)."""
    if prop.get("type") != "number":
        return text
    try:
        value = float(text)
    except ValueError:
        raise fail(f"'{text}' is not a number; {_allowed(prop)}") from None
    if not math.isfinite(value):
        raise fail(f"{text} is not a finite number; {_allowed(prop)}")
    return value


def _rows(sheet: Path) -> tuple[list[str], list[tuple[int, list[str]]]]:
    """The header and the data rows (numbered from 1, comments and blank lines skipped) of a
    tab-separated sheet."""
    try:
        text = sheet.read_text(encoding="utf-8-sig")  # a byte-order mark is not part of the first column's name
    except FileNotFoundError:
        raise SheetError(f"records sheet '{sheet}' does not exist; set campaign.sheet in the config to your sheet's path.") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise SheetError(f"records sheet '{sheet}' cannot be read ({exc}); give a tab-separated text file.") from None
    lines = [line for line in text.splitlines() if line.strip() and not line.lstrip().startswith("#")]
    if not lines:
        raise SheetError(f"records sheet '{sheet}' is empty; give a header line (record, path, ...) and one row per record.")
    table = list(csv.reader(lines, delimiter="\t"))
    header = [name.strip() for name in table[0]]
    other = _separated(header[0]) if len(header) == 1 else None
    if other:
        raise SheetError(f"records sheet '{sheet}': its header '{header[0]}' is one column whose names are separated by {other}; "
                         "separate the columns by tabs.")
    return header, list(enumerate(table[1:], start=1))


def _separated(cell: str) -> str | None:
    """The separator other than a tab (:data:`OTHER_SEPARATORS`, in words) that splits the
    cell ``cell``, or ``None``."""
    return next((words for sep, words in OTHER_SEPARATORS.items() if sep in cell.strip()), None)


def read_sheet(sheet: str | Path, *, simulated: str | Path = "results/simulated") -> list[dict]:
    """The rows of the campaign sheet ``sheet``, checked and completed, one dict a record.

    Each row's ``path`` is resolved against the sheet's folder (a row the workflow simulates
    gets ``<simulated>/<record>.nc``), defaults fill the empty cells (the schema's), ``dt`` is
    the step of the record (given, ``1/fs``, or read off the file's time axis: :func:`file_step`),
    ``block`` is the record's own id when none is given, and ``units_in_file`` says whether the
    file states its angle's units (else the row's ``units`` apply). A byte-order mark before
    the header is left out. A step a record file's reader refuses (``fs`` 1e-320) is left to
    the estimate, which refuses that record alone.

    Raises :class:`SheetError` naming the row and the column: an empty sheet, a sheet whose
    columns are separated by commas, semicolons or spaces rather than tabs, an unknown or
    missing column, a value the schema refuses (an unknown unit, a negative ``dt``, an unknown
    load ...), an id longer than :data:`MAX_ID`, a duplicate id, a missing file, both ``dt`` and
    ``fs``, a step that disagrees with the file's, no step at all, units that disagree with the
    file's, a simulated record longer than :data:`MAX_SIMULATED_POINTS` or whose step a float
    cannot hold, a block whose records differ in step or in their options.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (folder / "records.tsv").write_text("record\\tblock\\ttrue_e\\tdt\\tsimulate\\na1\\tA\\t0.9\\t0.8\\tseed=1\\n")
    >>> [(row["record"], row["block"], row["dt"]) for row in read_sheet(folder / "records.tsv", simulated=folder)]
    [('a1', 'A', 0.8)]
    >>> _ = (folder / "bad.tsv").write_text("record\\tpath\\tdt\\nb1\\tb1.npy\\t-1\\n")
    >>> read_sheet(folder / "bad.tsv")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    rockdec.pipeline.campaign.SheetError: records sheet '.../bad.tsv', row 1 (record 'b1'), column 'dt': '-1' is not allowed; give a finite number > 0.
    """
    import jsonschema

    sheet = Path(sheet)
    header, rows = _rows(sheet)
    props = schema()["properties"]
    for name in header:
        if name not in props:
            raise _fail(sheet, None, None, name, f"no such column; the columns are {', '.join(props)} (workflow/schemas/records.schema.yaml)")
    if len(set(header)) < len(header):
        twice = next(name for name in header if header.count(name) > 1)
        raise _fail(sheet, None, None, twice, "the header names this column twice; keep one")
    if "record" not in header:
        raise _fail(sheet, None, None, "record", "the header has no such column; every row needs a record id")
    if not rows:
        raise SheetError(f"records sheet '{sheet}' has a header but no record; add one row per record.")
    validator = jsonschema.Draft202012Validator(schema())
    out, seen = [], {}
    for number, cells in rows:
        if len(cells) > len(header):
            raise _fail(sheet, number, None, None, f"{len(cells)} cells for {len(header)} columns; separate the cells by tabs, one per column")
        if len(cells) == 1 < len(header) and _separated(cells[0]):
            raise _fail(sheet, number, None, None, f"one cell for {len(header)} columns, separated by {_separated(cells[0])}; "
                                                   "separate the columns by tabs")
        record = cells[0].strip() if header[0] == "record" and cells else None

        def fail(column, problem, number=number):
            return _fail(sheet, number, record, column, problem)

        row, raw = {}, {}
        for name, text in zip(header, cells):
            text = text.strip()
            if text:
                raw[name] = text
                row[name] = _typed(text, props[name], lambda problem, name=name: fail(name, problem))
        record = row.get("record")
        for column in ("record", "block"):
            if len(row.get(column, "")) > MAX_ID:
                raise fail(column, f"an id of {len(row[column])} characters ('{row[column][:12]}...'), more than the {MAX_ID} an id may have "
                                   "(its estimate's files are named by it); give a shorter id")
        errors = sorted(validator.iter_errors(row), key=lambda err: (header.index(err.path[0]) if err.path else -1))
        if errors:
            err = errors[0]
            column = err.path[0] if err.path else "record"
            value = err.instance
            if err.validator == "required":
                raise fail("record", "empty; every row needs a record id")
            raise fail(column, f"'{raw.get(column, value)}' is not allowed; {_allowed(props[column])}")
        if record in seen:
            raise fail("record", f"'{record}' is the id of row {seen[record]} too; give each record its own id")
        seen[record] = number
        out.append(_completed(row, sheet, Path(simulated), fail))
    _check_blocks(out, sheet, seen)
    return out


def _completed(row: dict, sheet: Path, simulated: Path, fail) -> dict:
    """A row with its defaults, its path resolved and its step known (:func:`read_sheet`)."""
    from rockdec.physics.record_model import check_filter_declared_with_model, parse_sensor_filter, parse_sensor_noise

    props = schema()["properties"]
    given_units = "units" in row
    row = {**{k: p["default"] for k, p in props.items() if "default" in p}, **row}
    row.setdefault("block", row["record"])
    if "dt" in row and "fs" in row:
        raise fail("fs", "both dt and fs are given; give the sampling as one of them")
    given = row.get("dt", 1.0 / row["fs"] if "fs" in row else None)
    if "simulate" in row:
        for column in ("true_e", "dt"):
            if column not in row:
                raise fail(column, f"a row the workflow simulates (simulate) needs its {column}")
        if "path" in row:
            raise fail("path", "a row the workflow simulates (simulate) writes its own file; leave path empty")
        row["path"] = str(simulated / f"{row['record']}.nc")
        row["simulate"] = simulation(row["simulate"], fail)
        span = (row["simulate"]["n_points"] - 1) * row["dt"]
        if not (row["dt"] >= np.finfo(np.float64).tiny and math.isfinite(span) and np.spacing(span) <= 0.5 * row["dt"]):
            raise fail("dt", f"a step of {row['dt']:g} s over {row['simulate']['n_points']} samples gives time stamps a float cannot "
                             "tell apart or hold; give a step like the demonstration's 0.8 s")
        row["units_in_file"] = True  # the simulated record's angle is stored in rad
        _simulated_shake(row, fail)
    else:
        if "path" not in row:
            raise fail("path", "empty; give the record's file (absolute, or relative to the sheet's folder)")
        path = _sheet_file(row["path"], sheet, lambda problem: fail("path", f"{problem}; give the record's file"))
        row["path"] = str(path)
        try:
            own, units = file_step(path, row["variable"], row["column"])
        except timeaxis.RecordError as exc:
            raise fail("path", str(exc).rstrip(".")) from None
        if units is not None and given_units and timeaxis.angle_factor(units, str(path), row["variable"]) != timeaxis.ANGLE_UNITS[row["units"]]:
            raise fail("units", f"'{row['units']}' differs from the file's own units '{units}'; leave units empty or give the file's")
        row["units_in_file"] = units is not None
        if own is not None and given is not None and abs(given - own) > STEP_RTOL * own:
            raise fail("dt" if "dt" in row else "fs", f"a step of {given:g} s disagrees with the file's time axis ({own:g} s); leave it empty or correct it")
        if own is None and given is None:
            raise fail("dt", f"'{path.name}' has no time axis; give the sampling step dt (s) or rate fs (Hz)")
        row["file_has_time"] = own is not None
        given = own if given is None else given
    row["dt"] = float(given)
    row.pop("fs", None)
    if row["test"] == "shake":
        _base_of(row, sheet, fail)
    elif "base" in row or "base_units" in row:
        column = "base" if "base" in row else "base_units"
        raise fail(column, "only a shake-table test (test shake) reads a base record; set test to shake, or leave it empty")
    if row["test"] != "random":
        why = no_record_model(row["test"])
        for column, default in (("g", None), ("load", "auto"), ("sensor_noise", "auto"), ("sensor_filter", "auto")):
            if row.get(column) != default and not (column == "g" and row["test"] == "shake"):
                raise fail(column, f"{why}; leave it empty")
        if row["share_lengths"] == "yes":
            raise fail("share_lengths", f"the {'free-rocking' if row['test'] == 'free' else 'shake-table'} test takes no calibration to share; "
                                        "leave it empty")
    if row["model"] == "housner" and "theta_cr" not in row:
        raise fail("theta_cr", "model housner needs the block's critical angle theta_cr in rad (atan(width/height))")
    if row["model"] != "housner" and "theta_cr" in row and row["test"] != "shake":
        raise fail("theta_cr", "theta_cr is the Housner model's critical angle; set model to housner, or leave it empty")
    try:
        row["load"] = load_option(row["load"], sheet)
    except InputError as exc:
        raise fail("load", str(exc).rstrip(".")) from None
    try:
        parse_sensor_noise(row["sensor_noise"])
    except InputError as exc:
        raise fail("sensor_noise", str(exc).rstrip(".")) from None
    try:  # "auto" is a part left to measure
        check_filter_declared_with_model(parse_sensor_filter(row["sensor_filter"]), None if row["load"] == "auto" else row["load"],
                                         None if row["sensor_noise"] == "auto" else row["sensor_noise"])
    except InputError as exc:
        raise fail("sensor_filter", str(exc).rstrip(".")) from None
    return row


def _on_sheet(text: str, sheet: Path) -> Path:
    """The path ``text`` of a sheet's cell: ``~`` expanded, absolute, or relative to the sheet's folder."""
    path = Path(text).expanduser()
    return path if path.is_absolute() else sheet.resolve().parent / path


def _sheet_file(text: str, sheet: Path, fail) -> Path:
    """The file a sheet's cell names (:func:`_on_sheet`); ``fail(problem)`` raises when it is a
    folder or does not exist."""
    path = _on_sheet(text, sheet)
    if not path.is_file():
        raise fail(f"'{path}' {'is a folder' if path.is_dir() else 'does not exist'}")
    return path


def _simulated_shake(row: dict, fail) -> None:
    """A simulated row's shake-table recipe (``shake=PEAK``) against its ``test``; such a row's
    base is stored beside its angle (:func:`simulated_record`) in rad/s^2 at ``g`` = 1."""
    shaken = row["simulate"]["shake"] is not None
    if shaken != (row["test"] == "shake"):
        raise fail("test" if shaken else "simulate", "a recipe with shake= simulates a shake-table test; set test to shake" if shaken else
                   "a shake-table row the workflow simulates needs shake=PEAK (the base's strength in uplift levels) in its recipe")
    if not shaken:
        return
    if "base" in row:
        raise fail("base", "a shake-table row the workflow simulates stores its base beside its angle; leave base empty")
    if row.get("base_units", "rad/s2") != "rad/s2" or row.get("g", 1.0) != 1.0:
        column = "g" if row.get("base_units", "rad/s2") == "rad/s2" else "base_units"
        raise fail(column, "the workflow simulates its shake-table tests at g = 1 rad/s^2 with the base in rad/s2; leave it empty")
    row.update(base=row["path"], base_variable="base", base_units="rad/s2", g=1.0, base_has_time=True)


def _base_of(row: dict, sheet: Path, fail) -> None:
    """A shake-table row's ``base``: its file resolved and checked (a time axis that agrees with
    the record's step, units stated or given, and the block's ``theta_cr`` or ``g`` they need)."""
    from rockdec.free.shake import BASE_UNITS, base_units_named

    if "simulate" not in row:
        if "base" not in row:
            raise fail("base", "empty; a shake-table test needs its base acceleration's file (it may be the record's own)")
        path = _sheet_file(row["base"], sheet, lambda problem: fail("base", f"{problem}; give the base acceleration's file"))
        row["base"] = str(path)
        try:
            own, units = file_step(path, row["base_variable"], row["base_column"])
        except timeaxis.RecordError as exc:
            raise fail("base", str(exc).rstrip(".").replace("in the variable column", "in the base_variable column")) from None
        if own is not None and abs(own - row["dt"]) > STEP_RTOL * row["dt"]:
            raise fail("base", f"the base is sampled every {own:g} s, the record every {row['dt']:g} s; resample the base onto the record's samples")
        named = None if units is None else base_units_named(units)
        if named is not None and named not in BASE_UNITS:
            raise fail("base", f"the base file's units '{units}' are not an acceleration rockdec reads; state m/s2, g or rad/s2")
        if named is not None and row.get("base_units", named) != named:
            raise fail("base_units", f"'{row['base_units']}' differs from the base file's own units '{units}'; leave base_units empty or give the file's")
        if named is None and "base_units" not in row:
            raise fail("base_units", f"'{path.name}' states no units for its base; give base_units m/s2, g or rad/s2")
        row["base_units"] = row.get("base_units", named)
        row["base_has_time"] = own is not None
    if row["base_units"] == "rad/s2" and "g" not in row:
        raise fail("g", "a base in rad/s2 (the rocking equation's load) needs the block's g in rad/s^2")
    if row["base_units"] != "rad/s2" and "theta_cr" not in row:
        raise fail("theta_cr", f"a base in {row['base_units']} needs the block's critical angle theta_cr in rad (atan(width/height))")


def _check_blocks(rows: list[dict], sheet: Path, numbers: dict) -> None:
    """The records of one block and one test (random or free: a block may hold both, each
    pooled apart) share their step (within :data:`STEP_RTOL`) and :data:`BLOCK_OPTIONS`."""
    first: dict[tuple, dict] = {}
    for row in rows:
        lead = first.setdefault((row["block"], row["test"]), row)
        number = numbers[row["record"]]
        if abs(row["dt"] - lead["dt"]) > STEP_RTOL * lead["dt"]:
            raise _fail(sheet, number, row["record"], "dt",
                        f"a step of {row['dt']:g} s differs from the {lead['dt']:g} s of record '{lead['record']}' of the same "
                        f"block '{row['block']}'; records pooled in one block share one step (resample it, or give it a block of its own)")
        for option in BLOCK_OPTIONS:
            if row.get(option) != lead.get(option):
                raise _fail(sheet, number, row["record"], option,
                            f"{row.get(option)!r} differs from record '{lead['record']}' of the same block '{row['block']}' "
                            f"({lead.get(option)!r}); the records of one block are pooled under one {option}")


def simulation(text: str, fail=None) -> dict:
    """The recipe of a ``simulate`` cell: ``seed=N`` and optional ``n_points=N`` (default
    200000), ``noise=SHARE`` (sensor noise as a share of the record's rms, default 0),
    ``corner=C`` (a low-pass load's corner in rocking frequencies, default white) and
    ``theta0=ANGLE`` (a free-rocking test: released from this tilt with no load) and
    ``shake=PEAK`` (a shake-table test: :func:`rockdec.physics.base_motion.shake_test` with the
    base's strong motion at ``PEAK`` uplift levels).

    Examples
    --------
    >>> simulation("seed=3 noise=0.03")
    {'seed': 3, 'n_points': 200000, 'noise': 0.03, 'corner': None, 'theta0': None, 'shake': None}
    """
    out = {"seed": None, "n_points": 200000, "noise": 0.0, "corner": None, "theta0": None, "shake": None}
    problem = None
    for part in text.split():
        key, _, value = part.partition("=")
        try:
            out[key] = float(value)
        except ValueError:
            problem = f"'{text}': {key}={value} is not a number; fix the recipe"
            continue
        if not math.isfinite(out[key]):
            problem = f"'{text}': {key}={value} is not a finite number; fix the recipe"
    if problem is None and out["n_points"] > MAX_SIMULATED_POINTS:
        problem = (f"'{text}' asks for {out['n_points']:.3g} samples, more than the {MAX_SIMULATED_POINTS:.0e} of the longest records "
                   f"whose interval's coverage was measured; give n_points <= {MAX_SIMULATED_POINTS}")
    if problem is None and (out["n_points"] < 1000 or out["noise"] < 0 or any(out[k] is not None and out[k] <= 0 for k in ("corner", "shake"))):
        problem = f"'{text}' asks for fewer than 1000 samples, a negative noise, or a corner or shake <= 0; fix the recipe"
    if problem is None and out["shake"] is not None and (out["theta0"] is not None or out["corner"] is not None):
        problem = f"'{text}': a shake-table test (shake=) is shaken by its base alone; leave theta0 and corner out"
    if problem is not None:
        if fail is None:
            raise SheetError(problem + ".")
        raise fail("simulate", problem)
    out["seed"], out["n_points"] = int(out["seed"]), int(out["n_points"])
    return out


def load_option(text: str, sheet: Path) -> str:
    """A ``load`` cell, checked (:func:`rockdec.physics.record_model.parse_load`), a table's or
    a base record's file made absolute against the sheet's folder; ``auto`` as is."""
    from rockdec.physics.record_model import parse_load

    if text == "auto":
        return text
    kind, sep, arg = text.partition(":")
    if kind in ("spectrum", "base"):
        text = f"{kind}:{_on_sheet(arg, sheet)}"
    parse_load(text, dt=1.0, points_per_cycle=1.0)  # a file is checked at a stand-in rocking frequency
    return text


def file_step(path: str | Path, variable: str = "theta", column: str = "theta") -> tuple[float | None, str | None]:
    """The step (s) of a record file's own time axis and the units its angle carries, from its
    header or first :data:`STEP_LINES` lines, never the whole record: ``(None, None)`` for a
    ``.npy`` file or a CSV without a ``time`` column."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix in (".nc", ".nc4", ".netcdf"):
        import netCDF4

        try:
            with netCDF4.Dataset(path) as ds:
                if variable not in ds.variables:
                    raise timeaxis.RecordError(f"'{path.name}' has no variable '{variable}'; name it in the variable column")
                var = ds.variables[variable]
                units = getattr(var, "units", None)
                dim = var.dimensions[-1]
                if dim in ds.variables:
                    coord = ds.variables[dim]
                    factor = timeaxis.time_factor(getattr(coord, "units", None), str(path), dim)
                    return timeaxis.sampling_step(coord[: STEP_LINES].data, str(path)) * factor, units
                step = getattr(var, "dt", getattr(ds, "dt", None))
                return (float(step) if step is not None else None), units
        except OSError as exc:
            raise timeaxis.RecordError(f"'{path.name}' is not a readable NetCDF file ({exc.strerror or exc})") from None
    if suffix in (".csv", ".txt"):
        with open(path, encoding="utf-8-sig", errors="replace") as f:  # as the reader, a byte-order mark left out
            lines = [line for _, line in zip(range(STEP_LINES), f) if line.strip() and not line.lstrip().startswith("#")]
        if not lines:
            raise timeaxis.RecordError(f"'{path.name}' is empty")
        sep = next((s for s in (",", ";", "\t") if s in lines[0]), None)
        names = [n.strip() for n in (lines[0].split(sep) if sep else lines[0].split())]
        if "time" not in names:
            return None, None
        index = names.index("time")
        try:
            times = [float((line.split(sep) if sep else line.split())[index]) for line in lines[1:]]
        except (ValueError, IndexError):
            raise timeaxis.RecordError(f"'{path.name}' has a time column that is not all numbers in its first lines") from None
        return timeaxis.sampling_step(times, str(path)), None
    if suffix == ".npy":
        return None, None
    raise timeaxis.RecordError(f"'{path.name}' is not a record format rockdec reads; give a .csv, .nc or .npy file")


# --- what the campaign's jobs compute -----------------------------------------------------


def units(rows: list[dict]) -> dict[str, list[dict]]:
    """The campaign's estimates: ``record_<id>`` for each record, ``block_<name>`` for each
    block of two or more random-response records, ``block_<name>-free`` for each block of
    two or more free-rocking tests and ``block_<name>-shake`` of shake-table tests (an id holds
    no ``-``: no block's name is another's tests'), each mapped to its rows (the records it pools)."""
    out = {f"record_{row['record']}": [row] for row in rows}
    blocks: dict[tuple, list[dict]] = {}
    for row in rows:
        blocks.setdefault((row["block"], row["test"]), []).append(row)
    out.update({f"block_{name}" + ("" if test == "random" else f"-{test}"): members for (name, test), members in blocks.items() if len(members) > 1})
    return out


def options(row: dict) -> dict:
    """The estimate options of a row (those of ``rockdec estimate``, :data:`BLOCK_OPTIONS`), as its job's params."""
    return {key: row.get(key) for key in BLOCK_OPTIONS}


def read(rows: list[dict]):
    """The records of ``rows`` as :class:`rockdec.record.records.Record` (their angles in rad),
    read as ``rockdec estimate`` reads them (:func:`rockdec.record.records.read_records`): the
    step passed only to a file without a time axis. What :func:`plan` analyses."""
    from rockdec.record import records

    out = []
    with locks.HDF5:
        for row in rows:
            for rec in records.read_records(row["path"], column=row["column"], variable=row["variable"], dt=_given_step(row)):
                factor = _angle_factor(row)
                out.append(rec if factor == 1.0 else rec._replace(theta=rec.theta * factor))
    return out


def _given_step(row: dict) -> float | None:
    """The step a row passes to the reader: its own for a file without a time axis, else none."""
    return None if row.get("file_has_time", row.get("simulate") is not None) else row["dt"]


def _angle_factor(row: dict) -> float:
    """The factor from the row's ``units`` to rad for a file that does not state its angle's
    units (a CSV or ``.npy`` file, a NetCDF variable without a ``units`` attribute); 1 for one
    that does, which the reader scales itself (``units_in_file``, :func:`read_sheet`)."""
    return 1.0 if row["units_in_file"] else timeaxis.ANGLE_UNITS[row["units"]]


def estimate(rows: list[dict], opts: dict, cache, api):
    """The estimate of the records of ``rows`` (pooled) under ``opts``: the one adapter
    between the workflow and the public estimate. ``api`` is the package's front door (the
    ``rockdec`` module), which the workflow hands in, this layer sitting beneath it: its
    ``read_record`` reads each file and its ``estimate`` returns a
    :class:`rockdec.RestitutionEstimate`, whose ``to_dict()`` is what ``rockdec estimate
    --json`` prints for the same files and options.

    Raises :class:`rockdec.validate.InputError` for records the estimate refuses.
    """
    return api.estimate(_theta(rows, api), g=opts.get("g"), load=opts["load"], sensor_noise=opts["sensor_noise"],
                        sensor_filter=opts["sensor_filter"], model=opts["model"], theta_cr=opts.get("theta_cr"), cache=cache,
                        share_lengths=_shares(opts))


def _shares(opts: dict) -> bool:
    """Whether the options ``opts`` share a calibration among records of nearby lengths (``share_lengths``)."""
    return opts.get("share_lengths") == "yes"


def _theta(rows: list[dict], api) -> list:
    """The records of ``rows`` as the front door ``api`` reads them (``read_record``), in rad."""
    theta = []
    with locks.HDF5:
        for row in rows:
            da = api.read_record(row["path"], column=row["column"], variable=row["variable"], dt=_given_step(row))
            theta.append(da if _angle_factor(row) == 1.0 else da.copy(data=da.values * _angle_factor(row)))
    return theta


def declared(opts: dict) -> dict:
    """The declared parts of the record model under ``opts`` as the estimate's stages take
    them, and as the public estimate passes them on
    (:func:`rockdec.physics.record_model.declared_load`, :func:`~rockdec.physics.record_model.parse_sensor_noise`,
    :func:`~rockdec.physics.record_model.parse_sensor_filter`)."""
    from rockdec.physics.record_model import declared_load, parse_sensor_filter, parse_sensor_noise

    return {"load": declared_load(opts["load"]), "sensor": parse_sensor_noise(opts["sensor_noise"]),
            "sensor_filter": parse_sensor_filter(opts["sensor_filter"])}


def plan(rows: list[dict], opts: dict, cache=None, earlier: dict | None = None) -> dict:
    """Which calibrations the estimate of ``rows`` (a record, or a block's records pooled)
    under ``opts`` reads, found by running that estimate
    itself (:func:`rockdec.estimation.estimate`, with the options the public estimate
    passes it), its repair's decisions included, allowed to read only the calibrations of the
    ``earlier`` plan (from ``cache``) and stopped at the first it asks for beyond them
    (:class:`rockdec.estimation.CalibrationNeeded`). The estimate reads at most two
    (the records' as given and, when the repair high-passes them, the high-passed records'):
    the plan without ``earlier`` finds the first, the plan on it, once built, the rest.

    Returns ``calibrations`` (file name in the cache -> settings, in the order the estimate
    asks for them) and ``error``, the estimate's refusal in its sentence (``None`` when it
    does not refuse the records). A plan that needs no calibration, or refuses, is final: the
    plan on it is itself.
    """
    from rockdec.calibrate import calibration
    from rockdec import estimation

    if earlier is not None and (earlier["error"] or not earlier["calibrations"]):
        return earlier
    known = dict(earlier["calibrations"]) if earlier is not None else {}
    done = {"calibrations": known, "error": None}
    if rows[0]["test"] != "random":
        return done
    available = {name.removeprefix("calibration-").removesuffix(".nc") for name in known}
    try:
        estimation.estimate(read(rows), cache_dir=cache, g=opts.get("g"), rocking=opts["model"],
                           theta_cr=opts.get("theta_cr"), available=available, length_grid=_shares(opts), **declared(opts))
    except estimation.CalibrationNeeded as need:
        known[f"calibration-{calibration.settings_hash(need.settings)}.nc"] = need.settings
    except InputError as exc:
        done["error"] = str(exc)
    return done


def build_calibration(settings: dict, cache) -> Path:
    """The calibration of ``settings`` built into (or found in) the folder ``cache``, the one
    ``rockdec estimate`` reads (:func:`rockdec.calibrate.calibration.load_or_build`); its path."""
    from rockdec.calibrate import calibration

    calibration.load_or_build(settings, cache)
    return Path(cache) / f"calibration-{calibration.settings_hash(settings)}.nc"


def free_rocking_unit(rows: list[dict], opts: dict, api):
    """A free-rocking test's estimate: ``free_rocking`` of the front door ``api`` on the records
    of ``rows`` (pooled), as ``rockdec estimate --test free`` runs it; ``None`` when this
    rockdec has no free-rocking analysis."""
    analysis = getattr(api, "free_rocking", None)
    if analysis is None:
        return None
    return analysis(_theta(rows, api), model=opts["model"], theta_cr=opts.get("theta_cr"))


def shake_unit(rows: list[dict], opts: dict, api):
    """A shake-table test's estimate: ``shake_table`` of the front door ``api`` on the records of
    ``rows`` (pooled) and their base records, as ``rockdec estimate --test shake`` runs it."""
    from rockdec.record import records

    bases = []
    with locks.HDF5:
        for row in rows:
            read, _ = records.read_base(row["base"], column=row["base_column"], variable=row["base_variable"],
                                        dt=None if row["base_has_time"] else row["dt"])
            bases += read
    theta = _theta(rows, api)
    return api.shake_table(theta if len(theta) > 1 else theta[0], bases if len(bases) > 1 else bases[0], base_units=opts["base_units"],
                           theta_cr=opts.get("theta_cr"), g_block=opts.get("g"), model=opts["model"])


def estimate_unit(rows: list[dict], opts: dict, cache, api) -> tuple[dict, object]:
    """The document of one record or block and its estimate: :func:`estimate`'s
    ``to_dict()`` (``rockdec estimate --json``) and the :class:`rockdec.RestitutionEstimate`;
    a refusal (:class:`rockdec.validate.InputError`) is a null ``e`` with the refusal as its
    ``reason`` and ``refused: true``, and no estimate; a free-rocking test goes to
    :func:`free_rocking_unit` (its reason :data:`FREE_UNAVAILABLE` when rockdec has none)."""
    test = rows[0]["test"]
    try:
        result = (free_rocking_unit(rows, opts, api) if test == "free" else shake_unit(rows, opts, api) if test == "shake" else
                  estimate(rows, opts, cache, api))
    except InputError as exc:
        return refused(rows, exc), None
    if result is None:
        return {"e": None, "interval": [None, None], "reason": FREE_UNAVAILABLE, "estimator": None, "test": "free",
                "records": [row["path"] for row in rows], "warnings": []}, None
    return result.to_dict(), result


def refused(rows: list[dict], exc: Exception) -> dict:
    """The document of records the estimate refuses: a null ``e``, the refusal as its reason."""
    return {"e": None, "interval": [None, None], "reason": str(exc), "estimator": None, "refused": True,
            "records": [row["path"] for row in rows], "warnings": []}


# --- the campaign's table: every record's and block's estimate side by side --------------

#: CF units of the document's numbers, by the last part of their name (``"1"`` otherwise).
UNITS = {"g": "rad s-2", "g_raw": "rad s-2", "g_interval": "rad s-2", "sigma_y": "rad", "dt": "s", "load_corner_hz": "Hz",
         "seconds": "s"}

def _units(field: str) -> str:
    """The CF units of the number ``field`` of a document (:data:`UNITS`, by its name's end)."""
    for suffix in ("_low", "_high", "_value", "_se"):
        field = field.removesuffix(suffix)
    return next((units for name, units in UNITS.items() if field == name or field.endswith(f"_{name}")), "1")


#: Parts of the document under which each key is an estimator or a check: a dimension each.
_BY = {"estimators": "estimator", "diagnostics": "check"}


def _numbers(doc, prefix: str = "") -> dict[str, float]:
    """Every number of the document ``doc`` (booleans as 0 and 1, nulls as NaN) by its path
    joined with ``_``; a pair (an interval) as ``_low`` and ``_high``; lists of text left out."""
    out: dict[str, float] = {}
    if isinstance(doc, dict):
        for key, value in doc.items():
            out.update(_numbers(value, f"{prefix}{key}_"))
    elif isinstance(doc, list):
        if len(doc) == 2 and all(v is None or isinstance(v, (int, float)) for v in doc):
            out[f"{prefix}low"] = math.nan if doc[0] is None else float(doc[0])
            out[f"{prefix}high"] = math.nan if doc[1] is None else float(doc[1])
    elif isinstance(doc, bool):
        out[prefix[:-1]] = float(doc)
    elif isinstance(doc, (int, float)):
        out[prefix[:-1]] = float(doc)
    return out


def unit_dataset(name: str, rows: list[dict], doc: dict):
    """The document of one record or block (:func:`estimate_unit`) as a CF dataset along
    ``record`` (length 1): every number of it, those per estimator along ``estimator`` and per
    check along ``check``; the reported estimator, the reason, the warnings and the simulated
    record model as text; the block, the kind (``record`` or ``block``) and the true ``e``
    (NaN when not known) as coordinates."""
    import xarray as xr

    data: dict = {}
    per: dict[str, dict] = {dim: {} for dim in _BY.values()}
    for part, dim in _BY.items():
        for key, sub in (doc.get(part) or {}).items():
            for field, value in _numbers(sub).items():
                per[dim].setdefault(f"{dim}_{field}", {})[key] = value
    rest = {k: v for k, v in doc.items() if k not in _BY and k not in ("selection",)}
    for field, value in {"e": math.nan, **_numbers(rest)}.items():  # a refused record's null e too
        data[field] = (("record",), [value], {"units": _units(field)})
    for dim, fields in per.items():
        keys = sorted({key for values in fields.values() for key in values})
        for field, values in fields.items():
            data[field] = (("record", dim), [[values.get(key, math.nan) for key in keys]], {"units": "1"})
        if keys:
            data[f"_{dim}"] = keys
    coords = {f"{dim}": (dim, data.pop(f"_{dim}")) for dim in _BY.values() if f"_{dim}" in data}
    model = ((doc.get("record_model") or {}).get("simulated") or {}).get("described", "")
    text = {
        "estimator_reported": doc.get("estimator") or "",
        "reason": doc.get("reason") or "",
        "warnings": "\n".join(doc.get("warnings") or []),
        "record_model": model,
    }
    for field, value in text.items():
        data[field] = (("record",), np.array([value], dtype=object), {"long_name": field.replace("_", " ")})
    true_e = rows[0].get("true_e") if all(r.get("true_e") == rows[0].get("true_e") for r in rows) else None
    kind = "block" if name.startswith("block_") else "record"
    test = rows[0].get("test", "random")
    pooled = f"{rows[0]['block']} ({ {'free': 'free tests', 'shake': 'shake-table tests'}.get(test, 'records')} pooled)"
    coords.update({
        "record": ("record", [name.split("_", 1)[1] if kind == "record" else pooled], {"long_name": "record, or a block's records pooled"}),
        "test": ("record", [test], {"long_name": "random (random response, Random Decrement), free (free-rocking test) or shake (shake-table test)"}),
        "block": ("record", [rows[0]["block"]], {"long_name": "block the record belongs to"}),
        "kind": ("record", [kind], {"long_name": "record, or block (its records pooled)"}),
        "true_e": ("record", [math.nan if true_e is None else float(true_e)], {"units": "1", "long_name": "coefficient of restitution the record was simulated with"}),
    })
    ds = xr.Dataset(data, coords=coords)
    for name_, var in ds.data_vars.items():
        var.attrs.setdefault("long_name", name_.replace("_", " "))
    return ds


def summary_dataset(datasets: list):
    """The unit datasets (:func:`unit_dataset`) of a campaign along ``record``, records first
    then blocks, each in the sheet's order."""
    import xarray as xr

    ds = xr.concat(datasets, dim="record", join="outer", data_vars="all", coords="minimal", compat="override", fill_value=np.nan)
    for name in ("estimator_reported", "reason", "warnings", "record_model"):
        ds[name] = ds[name].fillna("").astype(str)
    return ds


def table(ds):
    """One row per record and per block of the summary dataset ``ds``: its block, the true ``e``
    when known and whether the interval holds it, ``e``, the interval, the reported estimator,
    ``g``, the record model the calibration simulated, the warnings and the reason when ``e``
    is not given (a :class:`pandas.DataFrame`)."""
    import pandas as pd

    def holds(i):
        e, low, high, true = (float(ds[v][i]) for v in ("e", "interval_low", "interval_high", "true_e"))
        if math.isnan(true):
            return ""
        if math.isnan(e):
            return "no estimate"
        return "yes" if low <= true <= high else "no"

    n = ds.sizes["record"]
    rows = {
        "record": [str(v) for v in ds["record"].values],
        "kind": [str(v) for v in ds["kind"].values],
        "test": [str(v) for v in ds["test"].values] if "test" in ds.coords else ["random"] * n,
        "block": [str(v) for v in ds["block"].values],
        "true_e": ds["true_e"].values,
        "e": ds["e"].values,
        "low": ds["interval_low"].values,
        "high": ds["interval_high"].values,
        "holds_true_e": [holds(i) for i in range(n)],
        "estimator": [str(v) for v in ds["estimator_reported"].values],
        "g": ds["g"].values if "g" in ds else np.full(n, np.nan),
        "record_model": [str(v) for v in ds["record_model"].values],
        "warnings": [str(v).replace("\n", "; ") for v in ds["warnings"].values],
        "reason": [str(v) for v in ds["reason"].values],
    }
    out = pd.DataFrame(rows)
    return out if not out["true_e"].isna().all() else out.drop(columns=["true_e", "holds_true_e"])


def comparison(tab, tests: tuple[str, str] = ("random", "free")):
    """Per block that has both ``tests`` (the test names of :func:`units`), the second one's
    ``e`` beside the first one's (each the block's pooled estimate, or its one record's) with
    both 95 % intervals, and whether they agree (the intervals overlap); an empty table when
    no block has both. Columns ``block``, ``<test>_e``, ``<test>_low``, ``<test>_high`` of each
    test, ``agree``."""
    import pandas as pd

    def pick(part, test):
        rows = part[part["test"] == test]
        pooled = rows[rows["kind"] == "block"]
        return pooled.iloc[0] if len(pooled) else rows.iloc[0] if len(rows) == 1 else None

    first, second = tests
    columns = ["block", *(f"{t}_{q}" for t in tests for q in ("e", "low", "high")), "agree"]
    out = []
    for block in dict.fromkeys(tab["block"]):
        part = tab[tab["block"] == block]
        a, b = pick(part, first), pick(part, second)
        if a is None or b is None:
            continue
        known = all(math.isfinite(v) for v in (a["low"], a["high"], b["low"], b["high"]))
        agree = ("yes" if a["low"] <= b["high"] and b["low"] <= a["high"] else "no") if known else "no estimate"
        out.append(dict(zip(columns, [block, a["e"], a["low"], a["high"], b["e"], b["low"], b["high"], agree])))
    return pd.DataFrame(out, columns=columns)


#: The tests :func:`table_step` sets side by side per block, and the heading of each pair.
COMPARED = {("random", "free"): "The free-rocking test beside the random response, per block",
            ("free", "shake"): "The shake-table tests beside the free-rocking test, per block"}


def markdown(tab) -> str:
    """The campaign's table as Markdown: numbers to 3 decimals, a missing one blank."""
    shown = tab.copy()
    for column in ("true_e", "e", "low", "high", "g"):
        if column in shown:
            shown[column] = [("" if math.isnan(v) else f"{v:.3f}") for v in shown[column]]
    return shown.to_markdown(index=False) + "\n"


# --- the steps the campaign's rules run inside the Snakemake process ----------------------
# (rockdec.pipeline.in_snakemake.campaign): each reads and writes its files holding
# rockdec.locks.HDF5, since the HDF5 library under netCDF4 is used by one thread of a process at a time.


def simulated_record(row: dict):
    """The record of a ``simulate`` row as a dataset ``theta(time)`` (rad, s): the compiled
    kernel (:func:`rockdec.physics.simulate.simulate_block`, ``g = sigma_p = 1``) at ``true_e``
    and the row's ``dt``, the recipe's low-pass load placed at 75 samples per cycle (the
    coverage study's records, :mod:`rockdec.studies.coverage`), white sensor noise of the
    recipe's share of the record's rms (:func:`rockdec.physics.loading.add_sensor_noise`). A
    recipe with ``theta0`` is a free-rocking test: released from that tilt, no load, no
    burn-in, its noise a share of the release angle (as the free-rocking study draws it,
    :mod:`rockdec.studies.free_coverage`). A recipe with ``shake`` is a shake-table test
    (:func:`rockdec.physics.base_motion.shake_test`, its noise a share of the largest angle),
    its base acceleration (rad/s^2) stored beside the angle as ``base``."""
    import xarray as xr

    from rockdec.physics.base_motion import shake_test

    from rockdec.physics.loading import add_sensor_noise
    from rockdec.physics.record_model import Load
    from rockdec.physics.simulate import default_burn_in, simulate_block

    recipe, e, dt = row["simulate"], row["true_e"], row["dt"]
    placed_at = 75.0  # samples per cycle the coverage study places a load's corner at
    pole = (Load() if recipe["corner"] is None else Load("lowpass", recipe["corner"])).pole(placed_at)
    time = {"time": ("time", np.arange(recipe["n_points"]) * dt, {"units": "s", "standard_name": "time", "long_name": "time", "axis": "T"})}
    if recipe.get("shake") is not None:
        theta, base = shake_test(e, recipe["n_points"], dt, recipe["seed"], peak=recipe["shake"], noise=recipe["noise"])
        return xr.Dataset(
            {"theta": ("time", theta, {"units": "rad", "long_name": "rocking angle"}),
             "base": ("time", base, {"units": "rad s-2", "long_name": "base acceleration as the rocking equation's load"})},
            coords=time, attrs={"true_e": e},
        )
    if recipe.get("theta0") is None:
        theta = simulate_block([recipe["seed"]], recipe["n_points"], dt=dt, g=1.0, e=e, sigma_p=1.0,
                               burn_in=default_burn_in(e, placed_at), pole=pole)[0]
    else:
        theta = simulate_block([recipe["seed"]], recipe["n_points"], dt=dt, g=1.0, e=e, sigma_p=0.0, theta0=recipe["theta0"])[0]
    scale = abs(recipe["theta0"]) if recipe.get("theta0") is not None else float(np.sqrt(np.mean(theta**2)))
    add_sensor_noise(theta, [recipe["seed"]], recipe["noise"] * scale)
    return xr.Dataset({"theta": ("time", theta[0], {"units": "rad", "long_name": "rocking angle"})}, coords=time, attrs={"true_e": e})


def simulate_step(row: dict, output: str) -> str:
    """Rule ``campaign_simulate``: :func:`simulated_record` of ``row`` written to ``output``."""
    from rockdec import io

    ds = simulated_record(row)
    ds.attrs.update(io.provenance("campaign_simulate", {"record": row["record"], "true_e": row["true_e"], "dt": row["dt"], **row["simulate"]}))
    with locks.HDF5:
        io.write_netcdf(ds, output)
    return f"simulated {row['record']}: e = {row['true_e']}, {json.dumps(row['simulate'], sort_keys=True)}"


def _write_text(path: str, text: str) -> None:
    """Write ``path`` whole or not at all: the workflow reads the plans while others are written."""
    partial = Path(path).with_name(f".{Path(path).name}.partial")
    partial.write_text(text)
    os.replace(partial, path)


def plan_step(rows: list[dict], opts: dict, cache, earlier: str | None, output: str) -> str:
    """Rules ``campaign_first_plan`` (``earlier`` ``None``) and ``campaign_plan`` (``earlier``
    the first plan's file, its calibrations built into ``cache``): :func:`plan` of ``rows``
    written to ``output`` (JSON)."""
    done = plan(rows, opts, cache, None if earlier is None else json.loads(Path(earlier).read_text()))
    _write_text(output, json.dumps(done, indent=2, sort_keys=True) + "\n")
    return f"plan: {', '.join(done['calibrations']) or 'no calibration'}" + (f" ({done['error']})" if done["error"] else "")


def calibration_step(settings: dict, output: str, threads: int) -> str:
    """Rule ``campaign_calibration``: the calibration of ``settings`` (a plan's), built into the
    folder of ``output`` on ``threads`` (:func:`build_calibration`, on the engine of
    :mod:`rockdec.engine`)."""
    from rockdec import engine

    with engine.session(threads):
        path = build_calibration(settings, Path(output).parent)
    if str(path) != str(Path(output)):
        raise RuntimeError(f"the settings given name {path.name}, not {Path(output).name}")
    return f"calibration: {path}"


def estimate_step(unit: str, rows: list[dict], opts: dict, cache, plan_file: str, json_out: str, nc_out: str, step: str, api) -> str:
    """Rules ``campaign_record`` and ``campaign_block``: :func:`estimate_unit` of ``rows``
    written as JSON (what ``rockdec estimate --json`` prints) to ``json_out`` and as its CF
    dataset (``to_dataset()``; a refused or free-rocking row's :func:`unit_dataset`) to
    ``nc_out``; the calibration it used checked against its plan's (``plan_file``)."""
    from rockdec import io

    doc, result = estimate_unit(rows, opts, cache, api)
    if rows[0]["test"] == "random":
        planned = json.loads(Path(plan_file).read_text())["calibrations"]
        used = (doc.get("calibration") or {}).get("file")
        if used is not None and used not in planned:  # the plans run this estimate: a mismatch is a bug, not the user's
            raise RuntimeError(f"{unit}: the estimate used {used}, its plan built {', '.join(planned) or 'none'}")
    _write_text(json_out, json.dumps(doc, indent=2) + "\n")
    ds = result.to_dataset() if result is not None else unit_dataset(unit, rows, doc)
    for key, value in io.provenance(step, {"rows": rows, "options": opts}, inputs=[row["path"] for row in rows]).items():
        ds.attrs.setdefault(key, value)
    with locks.HDF5:
        io.write_netcdf(ds, nc_out)
    return f"{unit}: e = {doc.get('e')}"


def table_step(inputs: list[str], nc: str, csv_out: str, md: str, units_rows: dict) -> str:
    """Rule ``campaign_table``: the documents ``inputs`` (``estimates/<unit>.json``, of the
    units ``units_rows`` maps to their rows) as the campaign's dataset (:func:`unit_dataset`
    each, :func:`summary_dataset`) in ``nc``, its table (:func:`table`) in ``csv_out`` and
    ``md`` (:func:`markdown`)."""
    from rockdec import io

    datasets = [unit_dataset(Path(path).stem, units_rows[Path(path).stem], json.loads(Path(path).read_text())) for path in inputs]
    summary = summary_dataset(datasets)
    summary.attrs.update(io.provenance("campaign_table", {"units": list(units_rows)}, inputs=inputs))
    with locks.HDF5:
        io.write_netcdf(summary, nc)
    tab = table(summary)
    tab.to_csv(csv_out, index=False)
    text = markdown(tab)
    for tests, heading in COMPARED.items():
        shown = comparison(tab, tests)
        if not len(shown):
            continue
        for column in shown.columns[1:-1]:
            shown[column] = [("" if math.isnan(v) else f"{v:.3f}") for v in shown[column]]
        text += f"\n## {heading}\n\nagree: the two 95 % intervals overlap.\n\n" + shown.to_markdown(index=False) + "\n"
    _write_text(md, text)
    return f"{len(tab)} rows"
