"""Plotting, kept apart from the simulation (python-control's way): ``plot_response``."""

from __future__ import annotations

from typing import Any, Optional


def plot_response(response, ax: Optional[Any] = None, *, desired=None, title: Optional[str] = None):
    """Plot a ``StageResponse``: the measured position (um) against time (s), with the desired
    trajectory when given, on the matplotlib axes ``ax`` (a new figure's when ``None``; needs
    matplotlib, which hystcomp itself does not require). Returns the axes.

    Example: ``t, y = stage.run(volts)`` simulates; ``hystcomp.plot_response(stage.run(volts),
    desired=desired_um)`` plots.
    """
    if ax is None:
        try:
            import matplotlib.pyplot as plt
        except ImportError as error:  # pragma: no cover - depends on the environment
            raise ImportError("plot_response needs matplotlib: pip install matplotlib") from error
        _, ax = plt.subplots()
    time, outputs = response
    if desired is not None:
        ax.plot(time, desired, "k--", label="desired y_d")
    ax.plot(time, outputs, label="measured y")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("position (µm)")
    if title:
        ax.set_title(title)
    ax.legend()
    return ax
