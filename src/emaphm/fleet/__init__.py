"""The fleet: every actuator of a health history at a glance.

* :mod:`.status`: one actuator's state (verdict, the indicator nearest its threshold,
  RUL, trend) and the fleet's order of attention (:func:`assess`, :func:`order_fleet`);
* :mod:`.markup`: escaping of values written into HTML and inline JSON, safe file names;
* :mod:`.site`: the static site (:func:`build_site`): an index and a page per actuator,
  made again only where its inputs changed, in worker processes or on a Dask cluster;
* :mod:`.figures`: the pages' two figures as SVG (:class:`PageFigures`), written by
  :mod:`.svgplot` (panels of layers in data coordinates, rendered as text);
* :mod:`.demo`: a simulated fleet to fill a history (:func:`record_demo_fleet`);
* :mod:`.schedule`: the next inspection of every actuator as CSV or iCalendar;
* :mod:`.cli`: ``emaphm fleet report``, ``emaphm fleet demo`` and ``emaphm fleet schedule``.

This layer reads the prognosis layer and draws with its figures; it never identifies a
trace again, except :mod:`.demo`, which makes the inspections it records.
"""

from .._lazy import lazy_exports

_EXPORTS = {
    "ActuatorStatus": "status",
    "assess": "status",
    "attention_key": "status",
    "order_fleet": "status",
    "esc": "markup",
    "page_stem": "markup",
    "script_json": "markup",
    "slug": "markup",
    "FleetSite": "site",
    "build_site": "site",
    "PageFigures": "figures",
    "DemoUnit": "demo",
    "demo_fleet": "demo",
    "record_demo_fleet": "demo",
}

__getattr__, __dir__ = lazy_exports(__name__, globals(), _EXPORTS)

__all__ = list(_EXPORTS)
