"""The default blueprint: accepted by Rerun, and every entity the logger writes has a view."""

import rerun.blueprint as rrb

from stack.viz import layout as lay
from stack.viz.logger import TOPICS, FlightLogger, new_recording
from tests.viz.rrd import read_rrd


def view_origins(blueprint: rrb.Blueprint) -> list[str]:
    origins = []
    stack = [blueprint.root_container]
    while stack:
        node = stack.pop()
        if isinstance(node, rrb.View):
            origins.append(str(node.origin))
        else:
            stack.extend(node.contents)
    return origins


def test_blueprint_is_accepted_by_a_recording_and_by_a_file_sink(tmp_path):
    rec = new_recording("bp")
    memory = rec.memory_recording()
    rec.send_blueprint(lay.default_blueprint())
    rec.send_blueprint(lay.default_blueprint(window_s=None))
    assert memory.num_msgs() > 0
    path = tmp_path / "bp.rrd"
    rec = new_recording("bp-file")
    rec.save(path, default_blueprint=lay.default_blueprint())
    rec.flush()
    rec.disconnect()
    assert read_rrd(path).blueprints


def test_views_cover_the_scene_the_events_and_every_plotted_series(tmp_path):
    origins = view_origins(lay.default_blueprint())
    assert lay.WORLD in origins and lay.EVENTS in origins
    assert len(origins) == len(set(origins))
    path = tmp_path / "all.rrd"
    rec = new_recording("all")
    rec.save(path)
    logger = FlightLogger(rec, plot_rate_hz=0.0)
    for topic in TOPICS:
        logger.log_message(topic.name, 0, topic.type(timestamp=1000))
    logger.flush()
    rec.flush()
    rec.disconnect()
    written = read_rrd(path).entities() | {p for p, _ in lay.series_styles(4)}
    assert len(written) > 50
    for entity in written:
        assert any(entity == o or entity.startswith(o.rstrip("/") + "/") for o in origins), entity


def test_time_series_window_follows_the_cursor_or_shows_everything():
    def windows(blueprint):
        found = []
        stack = [blueprint.root_container]
        while stack:
            node = stack.pop()
            if isinstance(node, rrb.TimeSeriesView):
                found.append(node.properties.get("VisibleTimeRanges"))
            elif not isinstance(node, rrb.View):
                stack.extend(node.contents)
        return found

    live = windows(lay.default_blueprint(30.0))
    whole = windows(lay.default_blueprint(None))
    assert len(live) == len(whole) >= 20
    assert all(w is not None for w in live)
    assert all(w is None for w in whole)
