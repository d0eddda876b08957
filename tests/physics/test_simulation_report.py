"""What a simulation reports of what it made (issue 38): series that overturned under
Housner's model (eq. 2) counted against the simulator's own fall indices, and samples per
cycle that miss the requested ones stated."""

from __future__ import annotations

import dataclasses

import dask.array as da
import numpy as np
import pytest
import xarray as xr

from rockdec.physics import housner, run

hostile = pytest.mark.hostile

RUN = run.Run(model="housner", e=0.85, nu=2.0, theta_cr=0.25, sigma_p=0.01, dt=0.0034, burn_in=0, sigma_y=0.05,
              sigma_ydot=0.3, points_per_cycle=75.0, points_per_cycle_target=75.0)


@pytest.fixture(scope="module")
def fallen():
    """Housner series of which some overturn (sigma_p = 0.01 rad/s against theta_cr = 0.25 rad), with the fall indices."""
    seeds = np.arange(100, 108)
    theta, _, fell = housner.simulate_block_housner(seeds, 20_000, dt=0.0034, nu=2.0, theta_cr=0.25, e=0.85, sigma_p=0.01, burn_in=0)
    assert 0 < (fell >= 0).sum() < seeds.size  # some fall, some stand: the case the report is for
    return theta, fell, seeds


@hostile("wrong answers", "warned")
@pytest.mark.parametrize("form", ["numpy", "dataarray", "dask"])
def test_overturned_series_are_counted_as_the_simulator_says_they_fell(fallen, form):
    theta, fell, seeds = fallen
    given = {"numpy": theta, "dataarray": xr.DataArray(theta, dims=("seed", "time"), coords={"seed": seeds}),
             "dask": da.from_array(theta, chunks=(3, -1))}[form]
    result = run.overturned(given, seeds=None if form == "dataarray" else seeds)
    assert result.count == (fell >= 0).sum() and result.series == seeds.size
    assert result.seeds == tuple(int(s) for s in seeds[fell >= 0])
    assert result.worst == pytest.approx(max(1 - f / theta.shape[1] for f in fell if f >= 0), abs=1 / theta.shape[1])
    (line,) = run.simulation_report(given, RUN, seeds=None if form == "dataarray" else seeds)
    assert line.startswith(f"{result.count} of {seeds.size} series overturned") and "\n" not in line


@hostile("wrong answers", "answered")
def test_standing_series_at_the_requested_sampling_report_nothing(fallen):
    theta, fell, seeds = fallen
    standing = theta[fell < 0]
    assert run.simulation_report(standing, RUN) == [] and run.overturned(standing).count == 0


@hostile("wrong answers", "warned")
@pytest.mark.parametrize("got, want", [(25.9, 75.0), (60.0, 75.0), (2400.0, 2000.0), (9.0, 75.0)])
def test_samples_per_cycle_off_the_request_are_stated(got, want):
    contract = dataclasses.replace(RUN, points_per_cycle=got, points_per_cycle_target=want)
    line = run.points_per_cycle_shortfall(contract)
    off = abs(got / want - 1)
    if off <= run.PPC_TOLERANCE:
        assert line is None
    else:
        assert f"about {got:.3g} samples per rocking cycle" in line and f"not the {want:g} requested" in line
        assert f"{off:.0%} {'fewer' if got < want else 'more'}" in line
        assert run.simulation_report(np.zeros((1, 10)), contract) == [line]


@hostile("wrong answers", "answered")
@pytest.mark.parametrize("got", [75.0 * (1 - run.PPC_TOLERANCE) + 1e-9, 75.0, 75.0 * (1 + run.PPC_TOLERANCE) - 1e-9, float("nan")])
def test_samples_per_cycle_within_the_tolerance_or_unmeasured_pass(got):
    """Within the tolerance, or a free response (no sigma_Y: NaN), nothing is said."""
    assert run.points_per_cycle_shortfall(dataclasses.replace(RUN, points_per_cycle=got)) is None
