"""A negative coordinate in exponent form, as str() writes a small float, is a value on the command line."""

from stack.cli.app import cli, numbers_as_values


def test_a_negative_number_in_exponent_form_is_written_out_and_others_are_left_alone():
    args = ["cmd", "goto", "-5.0", "-2.1e-05", "-3E2", "--wait", "-e", "tcp/127.0.0.1:1"]
    assert numbers_as_values(args) == ["cmd", "goto", "-5.0", "-0.000021", "-300", "--wait", "-e", "tcp/127.0.0.1:1"]


def test_goto_reads_an_exponent_form_coordinate_as_east_not_as_an_endpoint():
    goto = cli().commands["cmd"].commands["goto"]  # type: ignore[attr-defined]
    ctx = goto.make_context("goto", numbers_as_values(["-5.0", "-2.1e-05", "-3.0"]))
    assert (ctx.params["north"], ctx.params["east"], ctx.params["down"]) == (-5.0, -2.1e-05, -3.0)
    assert ctx.params["endpoint"] is None
