"""The free-rocking figure draws a fit, a declined fit, and into given axes."""

import numpy as np
from matplotlib.figure import Figure

from rockdec.free.analysis import analyse_free_rocking
from rockdec.report.free_figures import plot_free_rocking
from rockdec.studies.free_coverage import free_record


def test_figure_marks_every_impact_and_release():
    theta, dt, _ = free_record(0.85, noise=0.01, samples_per_cycle=40, seed=1)
    fit = analyse_free_rocking(theta, dt)
    record_ax, e_ax = Figure().subplots(1, 2)
    fig = plot_free_rocking(fit, theta, dt, ax=(record_ax, e_ax))
    assert fig is record_ax.figure
    impacts = [line for line in record_ax.lines if line.get_label() == "impacts with e"][0]
    assert np.allclose(impacts.get_xdata(), fit.impact_time)
    assert len(e_ax.patches) == 1  # the pooled interval band


def test_figure_of_a_declined_fit_and_of_several_records_draws():
    theta, dt, _ = free_record(0.5, samples_per_cycle=12)
    fit = analyse_free_rocking(theta, dt)
    assert len(plot_free_rocking(fit, theta, dt).axes) == 2
    a, dt, _ = free_record(0.9, samples_per_cycle=30)
    assert len(plot_free_rocking(analyse_free_rocking([a, -a], dt), [a, -a], dt).axes) == 2
