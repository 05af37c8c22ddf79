from stack.commander.hysteresis import Hysteresis


def test_each_direction_has_its_own_time():
    h = Hysteresis(False)
    h.set_hysteresis_time_from(False, 100)
    h.set_hysteresis_time_from(True, 50)
    assert not h.set_state_and_update(True, 1000)
    assert not h.set_state_and_update(True, 1099)
    assert h.set_state_and_update(True, 1100)
    assert h.set_state_and_update(False, 2000)
    assert not h.set_state_and_update(False, 2050)


def test_a_request_that_flips_back_is_forgotten():
    h = Hysteresis(False)
    h.set_hysteresis_time_from(False, 100)
    h.set_state_and_update(True, 0)
    h.set_state_and_update(False, 60)
    assert not h.set_state_and_update(True, 120)
    assert not h.update(200)
    assert h.update(220)


def test_force():
    h = Hysteresis(True)
    h.set_hysteresis_time_from(True, 100)
    h.set_state_and_update(False, 0)
    h.force(True)
    assert h.update(1000)
