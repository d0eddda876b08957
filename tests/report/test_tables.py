"""Tables: the one function of replicate statistics (closed-form cases), and the CSV + Markdown ending."""

import math

import numpy as np
import pandas as pd
import pytest
import xarray as xr

from rockdec.calibrate import belt
from rockdec.report import tables

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


# --- the Markdown a reader reads -----------------------------------------------------

REPO = __import__("pathlib").Path(__file__).resolve().parents[2]


@pytest.fixture
def paper_table():
    """The paper table of 4 replicates of every estimator the paper reports, and one it does not."""
    rng = np.random.default_rng(1)
    names = ["e_g", "e_0", "e1", "e2", "e3", "e4", "e_v"]
    e_hat0 = xr.DataArray(rng.normal(0.95, 0.01, (7, 4)), dims=("estimator", "replicate"), coords={"estimator": names})
    return tables.summary_table(e_hat0, 0.95)


def markdown_rows(text: str) -> list[list[str]]:
    """The cells of a Markdown table (header first, the rule line left out)."""
    lines = [line for line in text.splitlines() if line.startswith("|") and not set(line) <= set("|-: ")]
    return [[cell.strip() for cell in line.strip("|").split("|")] for line in lines]


def test_markdown_shows_a_dash_where_there_is_no_value_never_nan(paper_table):
    text = tables.to_markdown(paper_table)
    assert "nan" not in text.lower()
    rows = {row[0]: row for row in markdown_rows(text)[1:]}
    header = markdown_rows(text)[0]
    assert rows["`e_v`"][header.index("paper: mean")] == tables.MISSING  # the paper has no e_v
    assert rows["`e_g`"][header.index("paper: std")] == tables.MISSING  # nor a spread of e_g


def test_markdown_says_a_column_of_one_value_once_and_leaves_out_the_other_weighting(paper_table):
    table = tables.with_alternative(paper_table, xr.DataArray(np.full((7, 4), 0.9), dims=("estimator", "replicate"),
                                                              coords={"estimator": paper_table["estimator"]}), "count_weights", 0.95)
    text = tables.to_markdown(table)
    first = text.splitlines()[0]
    assert "replicates: 4" in first and "true e: 0.95" in first
    header = markdown_rows(text)[0]
    assert len(header) == 9 and len(table.columns) == 13
    assert not any("weights" in h for h in header)


def test_markdown_prints_one_precision_per_column(paper_table):
    rows = markdown_rows(tables.to_markdown(paper_table))
    for k, heading in enumerate(rows[0][1:], start=1):
        decimals = {len(row[k].split(".")[1]) if "." in row[k] and "e" not in row[k] else None
                    for row in rows[1:] if row[k] != tables.MISSING}
        if heading != "p of the bias":  # p: two significant digits, however small
            assert len(decimals) == 1, (heading, decimals)


def test_the_docs_name_every_column_of_the_tables_in_words(paper_table):
    readme = (REPO / "docs" / "reference" / "tables.md").read_text()
    readings = pd.concat([paper_table.assign(reading=r) for r in ("pooled", "per_series")])
    readings = readings[["reading"] + list(paper_table.columns)]
    for table in (paper_table, readings):
        for heading in markdown_rows(tables.to_markdown(table))[0]:
            assert f"| {heading} |" in readme, heading
    for name in paper_table["estimator"]:
        assert f"| `{name}` |" in readme, name
