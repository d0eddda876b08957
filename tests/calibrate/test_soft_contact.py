"""A soft contact (issue 49): impacts whose velocity change is spread over a few samples,
made by a generator apart from the project's simulator (tests/soft_contact.py). The check
``filtered`` reads them as blunted; rockdec's calibration has instantaneous impacts (eq. 6)
and cannot model a soft contact, so ``e`` is declined whether ``sensor_filter`` is left to
be checked or declared none (a soft contact shifts ``e`` upwards, confidently)."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

import rockdec
from rockdec.calibrate import calibration
from rockdec import estimation
from rockdec.report.estimate_report import document
from stand_in_outcome import stand_in
from rockdec.physics.record_model import SensorFilter
from rockdec.physics.simulate import simulate_block
from rockdec.rdd import measured
from rockdec.record import diagnostics
from rockdec.record.records import Record

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from rocking_reference import flight_reference  # noqa: E402
from soft_contact import flight, soft_record  # noqa: E402

# As tests/calibrate/test_sensor_filter.py: about 75 samples per cycle at e = 0.9, g = sigma_p = 1.
DT, BURN_IN, E = 0.8043, 4362, 0.9
SMALL_GRID, SMALL_SETS = (0.6, 0.75, 0.85, 0.9, 0.95, 0.98), 6


def test_the_generator_without_contact_is_the_reference_flight():
    """``contact = 0`` is eq. 6's impact: flight by flight the pure-Python reference's."""
    rng = np.random.default_rng(3)
    for theta, omega, duration in zip(rng.normal(0.0, 50.0, 400), rng.normal(0.0, 10.0, 400), rng.uniform(0.1, 40.0, 400)):
        np.testing.assert_allclose(flight(theta, omega, duration, contact=0, e=E), flight_reference(theta, omega, duration, 1.0, E),
                                   rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("contact", [1.0, 1.5, 3.0])
def test_a_soft_contact_changes_the_velocity_linearly_over_its_steps(contact):
    """From ``theta = h`` falling at ``u0``: the crossing at ``t_c`` (``h - u0 t - t^2/2 = 0``,
    ``g = 1``) at speed ``V = u0 + t_c``; over the contact ``T = contact dt`` the velocity falls
    at ``g + (1 - e) V / T``, linearly, so it ends at ``e V - g T`` and the block ``V T - (g +
    (1 - e) V / T) T^2 / 2`` past zero; the ideal impact would leave ``e V`` at once."""
    h, u0, span = 50.0, 10.0, contact * DT
    t_c = -u0 + math.sqrt(u0 * u0 + 2.0 * h)
    speed = u0 + t_c
    decel = 1.0 + (1.0 - E) * speed / span
    for share in (0.25, 0.5, 1.0):
        t = share * span
        theta, omega = flight(h, -u0, t_c + t, contact=contact, e=E)
        assert omega == pytest.approx(-(speed - decel * t), rel=1e-9)
        assert theta == pytest.approx(-(speed * t - decel * t * t / 2.0), rel=1e-9)
    assert -flight(h, -u0, t_c + span, contact=contact, e=E)[1] == pytest.approx(E * speed - span, rel=1e-9)
    assert flight(h, -u0, t_c, contact=0, e=E)[1] == pytest.approx(-E * speed, rel=1e-12)


@pytest.fixture(scope="module")
def raw_reads():
    """Raw ``e_v``, ``e_0`` and ``filtered``'s statistic of 6 records each: the generator
    without contact, the project's kernel at the same ``e``, and the generator with a contact
    of 3 samples."""
    def read(y):
        a = measured.analyse([y], DT)
        return a.raw["e_v"], a.raw["e_0"], diagnostics.impact_sharpness(diagnostics.sums([y]), None)

    n, seeds = 30_000, range(6)
    return {
        "ideal": np.array([read(soft_record(s, n, contact=0, e=E)) for s in seeds]),
        "kernel": np.array([read(simulate_block([s], n, dt=DT, g=1.0, e=E, sigma_p=1.0, burn_in=BURN_IN)[0][0]) for s in seeds]),
        "soft": np.array([read(soft_record(s, n, contact=3, e=E)) for s in seeds]),
    }


def _apart(a, b):
    """The difference of the means of the columns of ``a`` and ``b`` over its standard error."""
    se = np.sqrt(a.var(axis=0, ddof=1) / len(a) + b.var(axis=0, ddof=1) / len(b))
    return (a.mean(axis=0) - b.mean(axis=0)) / se


def test_the_ideal_generator_reads_as_the_projects_simulator(raw_reads):
    """Without contact the generator's records give what the kernel's do at the same ``e``
    (raw ``e_v``, ``e_0`` and the sharpness of the impacts, within 3.5 standard errors of their
    difference); a contact of 3 samples raises raw ``e_v`` and makes every record's impacts
    blunter than any ideal record's."""
    assert np.all(np.abs(_apart(raw_reads["ideal"], raw_reads["kernel"])) < 3.5)
    clean = np.concatenate([raw_reads["ideal"], raw_reads["kernel"]])
    assert _apart(raw_reads["soft"], clean)[0] > 3.5
    assert raw_reads["soft"][:, 2].min() > clean[:, 2].max() > -1.0


@pytest.fixture(scope="module")
def small_calibrations(tmp_path_factory):
    """The cache of the small calibrations these tests build (6 values of ``e``, 12 sets
    each, 40,000-sample records; twice the sets of test_sensor_filter.py's, so that a clean
    record's threshold does not rest on the few largest of 6 sets)."""
    with pytest.MonkeyPatch.context() as monkeypatch:
        monkeypatch.setattr(calibration, "E_GRID", SMALL_GRID)
        monkeypatch.setattr(calibration, "SETS_PER_E", 2 * SMALL_SETS)
        monkeypatch.setattr(calibration, "SETS_PER_E_CAPPED", 2 * SMALL_SETS)
        yield tmp_path_factory.mktemp("soft-cache")


@pytest.mark.hostile("wrong answers", "refused")
@pytest.mark.parametrize("sensor_filter", ["auto", "none"])
@pytest.mark.parametrize("contact, e", [(3.0, 0.9), (1.5, 0.9), (3.0, 0.8)], ids=["3 samples", "1.5 samples", "3 samples, e 0.8"])
@pytest.mark.slow
def test_a_soft_contact_is_declined_naming_both_causes(small_calibrations, sensor_filter, contact, e):
    """A contact of 3 or 1.5 samples: ``filtered`` fires; checked for a filter, ``e`` is
    declined naming a filter and a soft contact; declared unfiltered (the advice a filter's
    decline once ended with, which gave ``e`` about 0.97 for 0.9, confidently), it is declined
    too, the reason first saying that none does not model a soft contact."""
    y = soft_record(7, 40_000, contact=contact, e=e)
    doc = rockdec.estimate(y, DT, sensor_filter=sensor_filter, cache=small_calibrations).to_dict()
    assert doc["diagnostics"]["filtered"]["fired"]
    assert doc["e"] is None and doc["interval"] == [None, None]
    assert "filtered: " in doc["reason"] and "soft contact" in doc["reason"] and "low-pass filter" in doc["reason"]
    assert doc["reason"].startswith("`sensor_filter` none was declared") == (sensor_filter == "none")
    assert not doc["record_model"]["measured"]["detected"]["colour"] and "point to a soft contact" in doc["reason"]


@pytest.mark.parametrize("make", ["generator", "kernel"])
def test_a_clean_record_declared_unfiltered_is_answered(small_calibrations, make):
    """Instantaneous impacts with ``sensor_filter`` none: ``filtered`` does not fire and ``e``
    is given, its interval holding the truth."""
    y = (soft_record(11, 40_000, contact=0, e=E) if make == "generator"
         else simulate_block([11], 40_000, dt=DT, g=1.0, e=E, sigma_p=1.0, burn_in=BURN_IN)[0][0])
    doc = rockdec.estimate(y, DT, sensor_filter="none", cache=small_calibrations).to_dict()
    assert not doc["diagnostics"]["filtered"]["fired"]
    assert doc["e"] is not None and doc["interval"][0] <= E <= doc["interval"][1]


@pytest.mark.parametrize("source, unfiltered, colour, declined, starts", [
    ("declared", True, True, True, "`sensor_filter` none was declared"),
    ("declared", True, False, True, "`sensor_filter` none was declared"),
    ("measured (none shown)", False, False, True, "the load measures white"),
    ("measured (none shown)", False, True, True, "the records show a defect"),
    ("declared", False, False, False, None),
], ids=["declared none", "declared none, white", "checked, white", "checked, coloured", "declared a filter or the whole model"])
def test_a_fired_filter_check_declines_unless_a_filter_was_declared(source, unfiltered, colour, declined, starts):
    """Declared unfiltered, a fired ``filtered`` declines ``e`` (a soft contact, which no
    declaration models), the reason saying so first; a load measured white points to a soft
    contact; a declared filter (or a record model declared whole) leaves it a warning."""
    verdict = estimation.Verdict(True, False, not colour, source == "declared", {"filtered": "the impacts' velocity jumps are spread"}, False)
    given = stand_in(verdict, e=0.97, estimator="e_v")
    out = estimation.decline_unrepaired(given, unfiltered)
    assert (out.declined is not None) == declined
    assert declined or out == given
    if declined:
        assert out.declined.startswith(starts) and ("point to a soft contact" in out.declined) == (not colour)
        assert "filtered: the impacts' velocity jumps are spread" in out.declined


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_first_order_filter_colours_a_white_load_and_a_soft_contact_does_not(seed):
    """The premise of the soft-contact hint: on white-load records, a contact of 1.5 or 3
    samples leaves the load read white, while a first-order filter after the block (causal at
    5 rocking frequencies, zero-phase at 20: gentle enough to pass the roll-off check) makes it
    read low-pass."""
    def read(y):
        choice = estimation.choose_model(estimation.analyse([Record(y, DT, "record")]))
        return choice.declined is None, choice.measurement.coloured

    for contact in (1.5, 3.0):
        assert read(soft_record(seed, 40_000, contact=contact, e=E)) == (True, False)
    y = soft_record(seed, 40_000, contact=0, e=E)
    ppc = measured.analyse([y], DT).points_per_cycle
    for found in (SensorFilter("rc", 1, 5.0, False), SensorFilter("rc", 1, 20.0, True)):
        assert read(found.apply(y, ppc)) == (True, True), found.text()


@pytest.mark.hostile("wrong answers", "refused")
@pytest.mark.parametrize("found", [SensorFilter("butterworth", 4, 5.0, True), SensorFilter("rc", 1, 5.0, False)], ids=lambda f: f.text())
@pytest.mark.slow
def test_a_filtered_record_declared_unfiltered_is_declined(small_calibrations, found):
    """A filter after the block that the user declares absent: the roll-off check is skipped
    (declared), the calibration simulates unfiltered records, and ``filtered`` fires; it
    declines ``e`` (it once only warned beside an interval that could miss), the reason
    saying that none was declared."""
    y = simulate_block([13], 40_000, dt=DT, g=1.0, e=E, sigma_p=1.0, burn_in=BURN_IN)[0][0]
    z = found.apply(y, measured.analyse([y], DT).points_per_cycle)
    doc = rockdec.estimate(z, DT, sensor_filter="none", cache=small_calibrations).to_dict()
    assert doc["diagnostics"]["filtered"]["fired"] and doc["e"] is None
    assert doc["reason"].startswith("`sensor_filter` none was declared") and "low-pass filter" in doc["reason"]
