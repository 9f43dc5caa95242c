"""The Foxglove layout for a DroneWrapper flight, built with ``foxglove.layouts``.

Left: the frontal camera with perception's boxes (the target green) above the map. Middle: a 3D
view of the local ENU frame following the drone, with its true pose and the target. Right: plots
of the controller's errors and commands, and its state. Topic names are the recorder's and the
live server's (:mod:`.views`); ``ns`` is the vehicle namespace.

    python -m dronewrapper.record.layout > docs/foxglove_layout.json
"""

from __future__ import annotations

from typing import Any, Literal

import foxglove.layouts as fl

from dronewrapper.msgs import registry
from dronewrapper.record.views import MAP_FRAME


def layout(ns: str = registry.DEFAULT_NAMESPACE, camera: str = "cam_frontal") -> fl.Layout:
    """The layout for vehicle namespace ``ns``."""
    image = "/" + registry.IMAGE_RAW.key(ns, camera=camera)
    boxes = "/" + registry.DETECTIONS.key(ns) + "/annotations"
    status = "/" + registry.CONTROLLER_STATUS.key(ns)
    fix = "/" + registry.GLOBAL_POSITION.key(ns) + "/fix"

    def plot(title_fields: list[tuple[str, str]]) -> fl.PlotPanel:
        return fl.PlotPanel(
            config=fl.PlotConfig(
                paths=[
                    fl.PlotSeries(value=f"{status}.{f}", label=label) for f, label in title_fields
                ],
                show_legend=True,
            )
        )

    camera_panel = fl.ImagePanel(
        config=fl.ImageConfig(
            image_mode=fl.ImageModeConfig(
                image_topic=image,
                annotations={boxes: fl.ImageAnnotationSettings(visible=True)},
            )
        )
    )
    scene = fl.ThreeDeePanel(
        config=fl.ThreeDeeConfig(
            follow_tf=f"{ns}/base_link", fixed_frame=MAP_FRAME, follow_mode="follow-position"
        )
    )
    errors = plot([("error_x", "forward error"), ("error_z", "vertical error px"),
                   ("error_yaw", "yaw error px")])  # fmt: skip
    commands = plot([("cmd_vx", "vx m/s"), ("cmd_vz", "vz m/s"), ("cmd_yaw_rate", "yaw rate")])
    state = fl.RawMessagesPanel(config=fl.RawMessagesConfig(topic_path=f"{status}.state"))
    fix_map = fl.MapPanel(config=fl.MapConfig(follow_topic=fix))
    return fl.Layout(
        content=_split(
            "row",
            (1, _split("column", (2, camera_panel), (1, fix_map))),
            (1, scene),
            (1, _split("column", (2, errors), (2, commands), (1, state))),
        )
    )


def _split(direction: Literal["row", "column"], *parts: tuple[int, Any]) -> fl.SplitContainer:
    """Panels side by side (``row``) or stacked (``column``), each given as (its proportion,
    the panel)."""
    return fl.SplitContainer(
        direction=direction,
        items=[fl.SplitItem(proportion=share, content=panel) for share, panel in parts],
    )


def layout_json(ns: str = registry.DEFAULT_NAMESPACE) -> str:
    """The layout as indented JSON (what ``docs/foxglove_layout.json`` holds)."""
    import json

    return json.dumps(json.loads(layout(ns).to_json()), indent=1) + "\n"


if __name__ == "__main__":
    print(layout_json(), end="")
