"""Tables: the one function of replicate statistics (closed-form cases), and the CSV + Markdown ending."""

import math

import numpy as np
import pandas as pd
import pytest
import xarray as xr

from rockdec import belt, tables

# --- replicate statistics ------------------------------------------------------------


def test_statistics_of_a_known_sample():
    # x = 1, 2, 6 against e = 1: deviations from the mean 3 are -2, -1, 3 (sum of squares 14)
    row = tables.bias_row([1.0, 2.0, 6.0], 1.0)
    assert list(row) == list(tables.STATISTICS)
    assert row["n"] == 3 and row["mean"] == pytest.approx(3.0) and row["bias"] == pytest.approx(2.0)
    assert row["std"] == pytest.approx(math.sqrt(7.0), rel=1e-14)  # 14 / (n - 1)
    assert row["rmse"] == pytest.approx(math.sqrt((0 + 1 + 25) / 3), rel=1e-14)
    assert row["ci95"] == pytest.approx(2.0 + belt.Z95 * math.sqrt(7.0), rel=1e-14)
    t = 2.0 / (math.sqrt(7.0) / math.sqrt(3.0))
    assert row["t"] == pytest.approx(t, rel=1e-14)
    # Student's t with 2 degrees of freedom: P(|T| > t) = 1 - t / sqrt(2 + t^2)
    assert row["p_value"] == pytest.approx(1.0 - t / math.sqrt(2.0 + t * t), rel=1e-12)


def test_an_unbiased_symmetric_sample_has_t_zero_and_p_one():
    row = tables.bias_row([0.9, 1.0], 0.95)
    assert row["bias"] == pytest.approx(0.0, abs=1e-15) and row["t"] == pytest.approx(0.0, abs=1e-12)
    assert row["p_value"] == pytest.approx(1.0)
    assert row["std"] == pytest.approx(math.sqrt(0.005), rel=1e-12) and row["rmse"] == pytest.approx(0.05, rel=1e-12)


@pytest.mark.parametrize("n", [2, 5, 40])
def test_rmse_identity(n):
    x = np.random.default_rng(n).normal(0.96, 0.01, n)
    row = tables.bias_row(x, 0.95)
    assert row["rmse"] ** 2 == pytest.approx(row["bias"] ** 2 + row["std"] ** 2 * (n - 1) / n, rel=1e-12)


def test_nan_and_infinite_estimates_are_left_out():
    x = [0.94, 0.955, 0.962, 0.951]
    with_gaps = tables.bias_row([np.nan, *x[:2], np.inf, *x[2:], np.nan], 0.95)
    assert with_gaps == pytest.approx(tables.bias_row(x, 0.95), rel=0, abs=0)
    assert with_gaps["n"] == 4


def test_one_estimate_has_no_spread_and_no_test():
    row = tables.bias_row([np.nan, 0.97], 0.95)
    assert row["n"] == 1 and row["mean"] == 0.97
    assert row["bias"] == pytest.approx(0.02) and row["rmse"] == pytest.approx(0.02)
    assert all(np.isnan(row[k]) for k in ("std", "ci95", "t", "p_value"))


@pytest.mark.parametrize("values", [[], [np.nan, np.nan]])
def test_no_estimate_gives_nan_statistics(values):
    row = tables.bias_row(values, 0.95)
    assert row["n"] == 0
    assert all(np.isnan(row[k]) for k in tables.STATISTICS if k != "n")


def test_equal_estimates_have_zero_spread_and_no_test():
    row = tables.bias_row([0.96, 0.96, 0.96], 0.95)
    assert row["std"] == 0.0 and row["ci95"] == pytest.approx(0.01) and row["rmse"] == pytest.approx(0.01)
    assert np.isnan(row["t"]) and np.isnan(row["p_value"])


def test_paper_table_keeps_its_columns():
    e_hat0 = xr.DataArray([[0.95, 0.96, np.nan]], dims=("estimator", "replicate"), coords={"estimator": ["e1"]})
    table = tables.summary_table(e_hat0, 0.95)
    assert list(table.columns) == ["estimator", "n", "mean", "std", "bias", "t", "p_value", "e_target",
                                   "paper_mean", "paper_std", "mean_minus_paper"]
    assert table.loc[0, "n"] == 2 and table.loc[0, "mean"] == pytest.approx(0.955)


# --- CSV + Markdown --------------------------------------------------------------------


def test_write_table_writes_every_digit_and_the_markdown_given(tmp_path):
    table = pd.DataFrame({"estimator": ["e1"], "mean": [0.123456789]})
    tables.write_table(table, tmp_path / "a.csv", tmp_path / "a.md")
    assert pd.read_csv(tmp_path / "a.csv")["mean"][0] == 0.123456789
    assert (tmp_path / "a.md").read_text() == tables.to_markdown(table) and "0.1235" in tables.to_markdown(table)
    tables.write_table(table, tmp_path / "b.csv", tmp_path / "b.md", markdown="# richer\n")
    assert (tmp_path / "b.md").read_text() == "# richer\n"
    assert (tmp_path / "b.csv").read_text() == (tmp_path / "a.csv").read_text()
