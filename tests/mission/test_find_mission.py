"""Missions found by path or by name, from any directory, as profiles are."""

import pytest

from stack.launch_files import find_mission, shipped_missions


def test_a_shipped_mission_is_found_by_name_from_any_directory(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert find_mission("box").name == "box.plan"  # a plan first, then a waypoint list
    assert find_mission("box.txt").name == "box.txt"
    assert find_mission("plane_rectangle").name == "plane_rectangle.plan"
    assert find_mission("box").read_text() == find_mission("box.plan").read_text()
    assert {"box.plan", "box.txt", "plane_rectangle.plan"} <= set(shipped_missions())


def test_a_path_is_the_file_it_names_and_a_name_is_not_looked_up_in_a_directory(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    mine = tmp_path / "box.plan"
    mine.write_text("{}")
    assert find_mission("box.plan") == mine.relative_to(tmp_path)  # the user's own file before the shipped one
    assert find_mission(mine) == mine
    with pytest.raises(FileNotFoundError, match="no such mission file"):
        find_mission(tmp_path / "elsewhere" / "box")


def test_an_unknown_name_is_refused_with_the_closest_and_the_shipped_ones(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(FileNotFoundError) as refused:
        find_mission("plane_rectangel")
    assert str(refused.value).startswith("plane_rectangel: no such mission file (did you mean plane_rectangle?)")
    assert "box.plan" in str(refused.value)
