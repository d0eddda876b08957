"""The result of an estimate of ``e``: one frozen object for people, machines and xarray.

:class:`RestitutionEstimate` holds the numbers as fields (``e``, its
``confidence_interval``, the ``coverage`` measured on the calibration's records, ...) and
the JSON document it was made from. ``summary()`` is the report an engineer reads,
``to_dict()``/``from_dict()`` the JSON document the command line prints (its schema,
:data:`SCHEMA_PATH`, ships with the package), ``to_dataset()`` a CF-1.10 dataset and
``plot()`` the figure of the reported estimator's signature and calibration.
"""

from __future__ import annotations

import copy
import dataclasses
import html
import json
from importlib import resources
from typing import TYPE_CHECKING, Any, NamedTuple

from rockdec.rdd import registry
from rockdec.report.summary import beyond_note, pct, reads
from rockdec.validate import InputError, in_range, is_finite_number, show

if TYPE_CHECKING:
    import pandas as pd
    import xarray as xr
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = ["ConfidenceInterval", "EstimateWarning", "RestitutionEstimate", "SCHEMA_VERSION", "check_document", "schema"]

#: Version of the JSON document (:meth:`RestitutionEstimate.to_dict`); a change of its keys
#: or their meaning raises it.
SCHEMA_VERSION = "1.0"

#: The JSON schema of the document, shipped in the package.
SCHEMA_PATH = "estimate.schema.json"

#: The confidence level of every interval rockdec reports.
CONFIDENCE_LEVEL = 0.95

#: Keys of the document that :meth:`RestitutionEstimate.to_dict` adds to the one
#: :func:`rockdec.estimation.estimate` writes.
ADDED_KEYS = ("schema_version", "test", "confidence_level")


class ConfidenceInterval(NamedTuple):
    """A 95 % confidence interval: ``low`` and ``high`` (``None`` when there is none).

    Examples
    --------
    >>> low, high = res.confidence_interval
    >>> low <= high
    True
    """

    low: float | None
    high: float | None


class EstimateWarning(NamedTuple):
    """A warning on an estimate: a stable ``code`` (a check's name, such as ``drift``) and its sentence.

    Examples
    --------
    >>> [w.code for w in res.warnings if w.code == "drift"]  # the record of the examples does not drift
    []
    """

    code: str
    message: str


def schema() -> dict:
    """The JSON schema of :meth:`RestitutionEstimate.to_dict`'s document.

    Returns
    -------
    dict
        The schema (draft 2020-12).

    Examples
    --------
    >>> from rockdec.report.result import schema
    >>> schema()["$defs"]["random"]["properties"]["schema_version"]["const"]
    '1.0'
    """
    return json.loads(resources.files("rockdec").joinpath(SCHEMA_PATH).read_text(encoding="utf-8"))


def check_document(doc) -> bool:
    """Refuse a document :meth:`RestitutionEstimate.from_dict` cannot read as an estimate;
    returns its test: ``"random"``, ``"free"`` (it has ``impacts``) or ``"shake"`` (it has
    ``impacts`` and ``shake_table``).

    Its keys ``e``, ``interval``, ``warnings`` and ``estimators`` (``impacts`` for a
    free-rocking test) must be there; ``schema_version``, when there, :data:`SCHEMA_VERSION`;
    ``warnings`` (and ``warning_codes``) lists of strings, one code a warning; ``interval``
    null or two numbers or nulls, ``low <= high``; ``e`` null (a declined estimate) or a
    finite number inside its interval, in [0, 1] for the random test (> 0 for a free-rocking
    or shake-table test, whose fitted line of log impact speeds may read e above 1).

    Raises
    ------
    InputError
        Naming the field and what it may hold.

    Examples
    --------
    >>> from rockdec.report.result import check_document
    >>> check_document(res.to_dict())
    'random'
    >>> check_document({**res.to_dict(), "e": 1.7})
    Traceback (most recent call last):
    ...
    rockdec.validate.InputError: `doc` e 1.7: outside [0, 1]; an estimate's e is null or a number in [0, 1] inside its interval.
    """
    if not isinstance(doc, dict):
        raise InputError(f"`doc` is a {type(doc).__name__}, not an estimate's JSON document (a dict, RestitutionEstimate.to_dict).")
    free = "impacts" in doc
    test = ("shake" if "shake_table" in doc else "free") if free else "random"
    missing = [key for key in ("e", "interval", "impacts" if free else "estimators", "warnings") if key not in doc]
    if missing:
        raise InputError(f"`doc` lacks {', '.join(missing)}: it is not an estimate's JSON document (RestitutionEstimate.to_dict).")
    version = doc.get("schema_version", SCHEMA_VERSION)
    if version != SCHEMA_VERSION:
        raise InputError(f"`doc` schema_version {show(version)} is not {SCHEMA_VERSION!r}, the only version this rockdec reads; "
                         "estimate the record again with this rockdec.")
    for key in ("warnings", "warning_codes"):
        value = doc.get(key) or []
        if not isinstance(value, list) or not all(isinstance(item, str) for item in value):
            raise InputError(f"`doc` {key} {_short(show(value))}: not a list of strings; give one string a warning, in a list.")
    if doc.get("warning_codes") and len(doc["warning_codes"]) != len(doc["warnings"]):
        raise InputError(f"`doc` has {len(doc['warning_codes'])} warning_codes for {len(doc['warnings'])} warnings; "
                         "give one code a warning.")
    pair = doc["interval"]
    if pair is not None and not (isinstance(pair, list) and len(pair) == 2
                                 and all(v is None or is_finite_number(v) for v in pair)):
        raise InputError(f"`doc` interval {_short(show(pair))}: not null nor a pair [low, high] of finite numbers (or nulls); "
                         "give the estimate's 95 % interval.")
    low, high = pair or (None, None)
    if low is not None and high is not None and low > high:
        raise InputError(f"`doc` interval [{show(low)}, {show(high)}] is reversed; give it as [low, high], low <= high.")
    e = doc["e"]
    if e is None:
        return test
    allowed = "a number > 0 inside its interval" if free else "a number in [0, 1] inside its interval"
    fix = f"an estimate's e is null or {allowed}"
    if free:
        in_range(e, "`doc` e", 0.0, lo_open=True, fix=fix)
    else:
        in_range(e, "`doc` e", 0.0, 1.0, fix=fix)
    if low is None or high is None or not low <= e <= high:
        raise InputError(f"`doc` e {show(e)} is outside its interval {show(pair)}; {fix}.")
    return test


def _interval(pair) -> ConfidenceInterval | None:
    return None if pair is None else ConfidenceInterval(*pair)


@dataclasses.dataclass(frozen=True, repr=False, eq=False)
class RestitutionEstimate:
    """The coefficient of restitution of a rocking block estimated from its records.

    Made by :func:`rockdec.estimate`; read back from its JSON document by :meth:`from_dict`.
    The examples use ``res = rockdec.estimate(rockdec.simulate(0.85, 20_000, seed=1))``.

    Attributes
    ----------
    e : float or None
        The reported estimate of ``e`` (the share of its angular velocity the block keeps
        at each impact, eq. 6), corrected for the bias of its estimator; ``None`` when no
        estimate can be trusted (``reason`` says why).
    confidence_interval : ConfidenceInterval
        Its 95 % interval (``low``, ``high``), by inverting the calibration's belt.
    confidence_level : float
        0.95.
    coverage : float or None
        Share of the calibration's simulated records whose interval held their true ``e``.
    estimator : str or None
        The estimator reported (``e_v``, ``e_0`` or ``e4``).
    reason : str or None
        Why ``e`` is ``None``.
    g : float or None
        The block's restoring acceleration ``nu^2 theta_cr`` (rad/s^2, eq. 4): read off the
        record and corrected, or as given. Not gravity.
    g_interval : ConfidenceInterval or None
        Its 95 % interval, when the calibration gives one.
    record_model : dict
        What besides ``e`` makes the record (load, sensor noise, rocking model): measured,
        declared, and what the calibration simulated.
    warnings : tuple of EstimateWarning
        What looks wrong with the record, each with a stable code.
    diagnostics : dict
        Each check's statistic, threshold and whether it fired.
    rockdec_version : str
        The version that made the estimate.
    test : str
        ``"random"``: the random-response test (Random Decrement, :func:`rockdec.estimate`);
        ``"free"``: the free-rocking test (:func:`rockdec.free_rocking`); ``"shake"``: the
        free-decay tails of a shake-table test (:func:`rockdec.shake_table`).

    Examples
    --------
    >>> res.e is None or res.confidence_interval.low <= res.e <= res.confidence_interval.high
    True
    >>> res.to_dict()["estimator"] == res.estimator
    True
    """

    e: float | None
    confidence_interval: ConfidenceInterval
    confidence_level: float
    coverage: float | None
    estimator: str | None
    reason: str | None
    g: float | None
    g_interval: ConfidenceInterval | None
    record_model: dict
    warnings: tuple
    diagnostics: dict
    rockdec_version: str
    test: str
    document: dict = dataclasses.field(repr=False)
    analysis: Any = dataclasses.field(default=None, repr=False)
    belts: Any = dataclasses.field(default=None, repr=False)

    @classmethod
    def from_dict(cls, doc: dict, *, analysis=None, belts=None) -> RestitutionEstimate:
        """The estimate of a JSON document (:meth:`to_dict`, as the command line prints it).

        Parameters
        ----------
        doc : dict
            The document.
        analysis, belts : optional
            The signatures and calibration belts :meth:`plot` draws (not in the document).

        Returns
        -------
        RestitutionEstimate

        Raises
        ------
        InputError
            When ``doc`` is not such a document (``rockdec.report.result.check_document``).

        Examples
        --------
        >>> import json, rockdec
        >>> back = rockdec.RestitutionEstimate.from_dict(json.loads(json.dumps(res.to_dict())))
        >>> back.e == res.e and back.to_dict() == res.to_dict()
        True
        """
        test = check_document(doc)
        free = test != "random"
        doc = {key: copy.deepcopy(value) for key, value in doc.items() if key not in ADDED_KEYS}
        codes = doc.get("warning_codes") or ["warning"] * len(doc["warnings"])
        return cls(
            e=doc["e"],
            confidence_interval=ConfidenceInterval(*(doc["interval"] or [None, None])),
            confidence_level=CONFIDENCE_LEVEL,
            coverage=doc.get("coverage"),
            estimator=doc.get("estimator"),
            reason=doc.get("reason"),
            g=doc.get("g"),
            g_interval=_interval(doc.get("g_interval")),
            record_model=doc.get("record_model") or ({"model": doc["model"], "theta_cr": doc.get("theta_cr")} if free else {}),
            warnings=tuple(EstimateWarning(c, m) for c, m in zip(codes, doc["warnings"])),
            diagnostics=doc.get("diagnostics") or {},
            rockdec_version=doc.get("rockdec_version", ""),
            test=test,
            document=doc,
            analysis=analysis,
            belts=belts,
        )

    def to_dict(self) -> dict:
        """The JSON document of the estimate, exactly what the command line prints as JSON.

        Returns
        -------
        dict
            JSON-able (numbers, strings, lists, ``None``), with ``schema_version``; it
            validates against :func:`rockdec.report.result.schema`.

        Examples
        --------
        >>> doc = res.to_dict()
        >>> doc["schema_version"], doc["e"] == res.e
        ('1.0', True)
        """
        return {"schema_version": SCHEMA_VERSION, "test": self.test, "confidence_level": self.confidence_level,
                **copy.deepcopy(self.document)}

    @property
    def estimators(self) -> pd.DataFrame:
        """Every estimator of ``e`` on the record: one row each, with its ``raw`` value,
        ``corrected`` value, 95 % interval (``low``, ``high``), calibrated ``coverage``,
        ``triggers``, whether it is a ``candidate`` for the report, and ``notes``.

        Examples
        --------
        >>> list(res.estimators.columns)[:4]
        ['reads', 'raw', 'corrected', 'low']
        """
        import pandas as pd

        if self.test != "random":
            notes = "; ".join(w.message for w in self.warnings)
            table = self.document.get("shake_table", {})
            tails = {"e": table["tails_e"], "interval": table["tails_interval"]} if "tails_e" in table else self.document
            rows = [{"estimator": "impacts", "reads": "line of the log impact speeds of the free-rocking test", "raw": None,
                     "corrected": tails["e"], "low": tails["interval"][0], "high": tails["interval"][1], "coverage": None,
                     "triggers": len(self.document["impacts"]), "candidate": True, "reported": self.estimator == "impacts", "notes": notes}]
            forced = self.document.get("shake_table", {}).get("forced")
            if forced is not None:
                rows.append({"estimator": "forced", "reads": "every impact, the base a known load in the flights", "raw": None,
                             "corrected": forced["e"], "low": forced["interval"][0], "high": forced["interval"][1], "coverage": None,
                             "triggers": forced["impacts"], "candidate": True, "reported": self.estimator == "forced",
                             "notes": forced["reason"] or ""})
            return pd.DataFrame(rows).set_index("estimator")
        rows = []
        for name, est in self.document["estimators"].items():
            shown = est["e"] is not None
            rows.append({
                "estimator": name, "reads": reads(name), "raw": est["raw"], "corrected": est["e"],
                "low": est["interval"][0] if shown else None, "high": est["interval"][1] if shown else None,
                "coverage": est["coverage"], "triggers": est["triggers"], "candidate": name in registry.CANDIDATES,
                "reported": name == self.estimator, "notes": "; ".join(([beyond_note(est)] if est.get("beyond") else []) + est["notes"]),
            })
        return pd.DataFrame(rows).set_index("estimator")

    @property
    def impacts(self) -> pd.DataFrame:
        """The impacts of a free-rocking test, one row each: record, release, time (s), apex
        of the flight before (rad), angular velocities before and after (rad/s) with their
        standard errors, ``e`` and its standard error (empty for the random test).

        Examples
        --------
        >>> res.impacts.empty  # the random test has no impacts
        True
        """
        import pandas as pd

        return pd.DataFrame(self.document.get("impacts", []))

    def __repr__(self) -> str:
        if self.e is None:
            return f"RestitutionEstimate(e=None, reason={_short(self.reason)!r})"
        low, high = self.confidence_interval
        return (f"RestitutionEstimate(e={self.e:.4f}, 95% CI=[{low:.4f}, {high:.4f}], estimator={self.estimator!r}, "
                f"warnings={len(self.warnings)})")

    def _repr_html_(self) -> str:
        rows = "".join(f"<tr><td>{html.escape(k)}</td><td>{html.escape(v)}</td></tr>" for k, v in self._headline())
        warn = "".join(f"<li><code>{html.escape(w.code)}</code>: {html.escape(w.message)}</li>" for w in self.warnings)
        return (f"<div><strong>RestitutionEstimate</strong><table>{rows}</table>"
                + (f"<p>warnings:</p><ul>{warn}</ul>" if warn else "") + "</div>")

    def _headline(self) -> list[tuple[str, str]]:
        """(label, text) pairs of the main numbers, for the HTML view."""
        if self.e is None:
            return [("e", "not estimated"), ("reason", self.reason or "")]
        low, high = self.confidence_interval
        out = [("e", f"{self.e:.4f}"), ("95 % interval", f"[{low:.4f}, {high:.4f}]"), ("estimator", str(self.estimator)),
               ("coverage on the calibration's records", pct(self.coverage))]
        if self.g is not None:
            out.append(("restoring acceleration g (rad/s²)", f"{self.g:.5g}"))
        return out

    def summary(self, verbose: bool = False) -> str:
        """The report of the estimate, in words an engineer reads without the paper at hand.

        Parameters
        ----------
        verbose : bool
            Also list every estimator with its notes, the record model as measured, the
            calibration and the checks.

        Returns
        -------
        str

        Examples
        --------
        >>> print(res.summary().splitlines()[0])  # doctest: +ELLIPSIS
        e = ... (95 % interval [..., ...]; estimator ...)
        """
        if self.test == "shake":
            from rockdec.report.shake_result import shake_text

            return shake_text(self.document, verbose)
        if self.test == "free":
            from rockdec.report.free_result import free_text

            return free_text(self.document, verbose)
        from rockdec.report.summary import text

        return text(self.document, verbose)

    def to_dataset(self) -> xr.Dataset:
        """The estimate as a CF-1.10 dataset: the reported ``e`` with its interval bounds
        (``e_low``, ``e_high``, linked by ``ancillary_variables``), each estimator's raw
        and corrected value and interval along an ``estimator`` dimension, ``g`` and its
        interval; the JSON document in the attribute ``rockdec_estimate``.

        Returns
        -------
        xarray.Dataset

        Examples
        --------
        >>> ds = res.to_dataset()
        >>> float(ds["e"]) == res.e, ds["e"].attrs["units"]
        (True, '1')
        """
        if self.test != "random":
            from rockdec.report.free_result import free_dataset

            return free_dataset(self)
        from rockdec.report.result_dataset import dataset

        return dataset(self)

    def plot(self, ax: Axes | None = None) -> Figure:
        """The signature of the reported estimator beside its calibration belt (for a
        free-rocking test: the record with its fitted flights, and ``e`` per impact).

        Parameters
        ----------
        ax : matplotlib Axes, optional
            Two axes to draw in (a sequence), or ``None`` for a new figure.

        Returns
        -------
        matplotlib.figure.Figure

        Raises
        ------
        InputError
            For an estimate read back from its document, which carries no signatures, and a
            shake-table estimate without a free-decay tail (the figure draws the tails).

        Examples
        --------
        >>> fig = res.plot()
        >>> len(fig.axes)
        2
        """
        if self.analysis is None and self.test == "shake" and self.estimator != "impacts":
            raise InputError("this shake-table estimate has no free-decay tail to draw (the figure draws the tails' fits); "
                             "its readings of every impact are in to_dict()['shake_table']['forced'].")
        if self.analysis is None:
            raise InputError(
                "this estimate was read back from its document, which carries no signatures to plot; "
                "estimate the record again (rockdec.estimate) to plot it."
            )
        if self.test != "random":
            from rockdec.report.free_figures import plot_free_rocking

            fit, theta, dt = self.analysis
            return plot_free_rocking(fit, theta, dt, ax)
        from rockdec.report.figures import fig_record

        return fig_record(self, ax)


def _short(text: str | None, n: int = 80) -> str | None:
    return text if text is None or len(text) <= n else text[: n - 1] + "…"
