"""Meshcat browser controls of the planner app: buttons, sliders and a two-line status.

Drake's Meshcat offers buttons (``AddButton`` / ``GetButtonClicks``) and sliders
(``AddSlider`` / ``GetSliderValue`` / ``SetSliderValue``) in the page's control panel, but no
drop-down and no text element (pydrake 1.51: checked with ``dir(Meshcat)``). So:

* choices (robot, algorithm, which path point the sliders edit) are buttons that *cycle*
  through the options ("Next robot", "Next algorithm", "Edit next point"); the current choice
  is shown in the setup line;
* the status is shown as the label of two inert buttons at the bottom of the panel
  ("Setup: ..." and "Status: ..."); a new text deletes and re-adds them (they stay last).

Meshcat lists these controls below its own folders; the app's page
(:mod:`drake_mh.viz.app_page`) shows them first, grouped by :data:`SECTIONS`, with the status
lines as a status box on top.

:class:`Controls` polls clicks and slider changes without callbacks (Meshcat has none): the
app's loop calls :meth:`Controls.clicked` and :meth:`Controls.changed` every frame, in the
thread that created the Meshcat instance (a Drake requirement).
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Controls", "SliderSpec", "BUTTONS", "SECTIONS", "STATUS_PREFIXES", "MAX_GOAL_JOINTS", "joint_slider_name"]

MAX_GOAL_JOINTS = 12
"""Goal joint sliders the page has places for (a robot with more joints: the rest are listed
after the sections)."""


def joint_slider_name(i: int) -> str:
    """Name of the slider of joint ``i`` (0-based) of the planning goal configuration."""
    return f"Goal joint {i + 1}"


#: the app's buttons in panel order (framework paper Table 1: parts 1, 2, 4, 5/7; then planning)
BUTTONS = (
    "Next robot",
    "Next algorithm",
    "Edit next point",
    "Show environment",
    "Generate / Regenerate solutions",
    "Test run",
    "Run",
    "Stop",
    "Plan to goal pose",
    "Plan to goal joints",
    "Next planner",
)

#: the app page's sections (Table 1's parts) and their controls, in order
SECTIONS = (
    ("1 · Robot and algorithm", ("Next robot", "Next algorithm")),
    ("2 · Path", ("Edit next point", "Point X [m]", "Point Y [m]", "Point Z [m]", "Points in path")),
    ("3-5, 7 · Solve and run", ("Generate / Regenerate solutions", "Test run", "Run", "Stop", "Show environment")),
    ("6 · Obstacle (moves live)", ("Obstacle X [m]", "Obstacle Y [m]", "Obstacle Z [m]", "Obstacle radius [m]")),
    ("8 · Plan a motion", ("Plan to goal pose", "Plan to goal joints", "Next planner", "Plan timeout [s]",
                           "Goal X [m]", "Goal Y [m]", "Goal Z [m]",
                           *(joint_slider_name(i) for i in range(MAX_GOAL_JOINTS)))),
)

#: labels of the inert status buttons start with these (the page shows them as its status box)
STATUS_PREFIXES = ("Setup: ", "Status: ")


@dataclass(frozen=True)
class SliderSpec:
    """A slider: label, range, step and initial value (units in the label)."""

    name: str
    low: float
    high: float
    step: float
    value: float


class Controls:
    """Buttons, sliders and status lines in Meshcat's control panel (module docstring).

    Args:
        meshcat: the ``pydrake.geometry.Meshcat`` (used from its own thread only).
        sliders: the :class:`SliderSpec` list, added after the buttons.
    """

    def __init__(self, meshcat, sliders):
        self.meshcat = meshcat
        self._clicks: dict[str, int] = {}
        self._values: dict[str, float] = {}
        self._status_labels: list[str] = []
        meshcat.DeleteAddedControls()
        for name in BUTTONS:
            meshcat.AddButton(name)
            self._clicks[name] = 0
        for spec in sliders:
            self._values[spec.name] = float(meshcat.AddSlider(spec.name, spec.low, spec.high, spec.step, spec.value))

    @property
    def slider_names(self) -> list[str]:
        """Names of the sliders."""
        return list(self._values)

    def clicked(self) -> list[str]:
        """Buttons clicked since the last call (each once, in panel order)."""
        out = []
        for name, seen in self._clicks.items():
            count = self.meshcat.GetButtonClicks(name)
            if count != seen:
                self._clicks[name] = count
                out.append(name)
        return out

    def changed(self) -> dict[str, float]:
        """``{slider: new value}`` of the sliders moved in the browser since the last call."""
        out = {}
        for name, seen in self._values.items():
            value = float(self.meshcat.GetSliderValue(name))
            if value != seen:
                self._values[name] = value
                out[name] = value
        return out

    def add_slider(self, spec: SliderSpec) -> None:
        """Adds a slider (e.g. one per joint of a newly loaded robot)."""
        self._values[spec.name] = float(self.meshcat.AddSlider(spec.name, spec.low, spec.high, spec.step, spec.value))

    def remove_slider(self, name: str) -> None:
        """Deletes a slider added before."""
        if self._values.pop(name, None) is not None:
            self.meshcat.DeleteSlider(name)

    def value(self, name: str) -> float:
        """Current value of a slider."""
        return self._values[name]

    def set(self, name: str, value: float) -> None:
        """Set a slider from the app (not reported by :meth:`changed`)."""
        self.meshcat.SetSliderValue(name, float(value))
        self._values[name] = float(self.meshcat.GetSliderValue(name))

    def status(self, *lines: str) -> None:
        """Show ``lines`` as the labels of inert buttons at the bottom of the panel."""
        # a quote in a control's name breaks Meshcat's page (the control never appears): drop them
        labels = [line.replace("\n", " ").replace("'", "").replace('"', "")[:160] for line in lines]
        if labels == self._status_labels:
            return
        for old in self._status_labels:
            self.meshcat.DeleteButton(old)
        unique = []
        for label in labels:  # Meshcat identifies controls by name: keep them distinct
            while label in unique or label in self._clicks or label in self._values:
                label += " "
            unique.append(label)
            self.meshcat.AddButton(label)
        self._status_labels = unique
