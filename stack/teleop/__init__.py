"""Flying by hand from a terminal: the logic of ``stack teleop``, free of I/O.

The keyboard (:mod:`.keys` decodes a terminal's bytes, :mod:`.keyboard` turns presses into sticks), the Linux
joystick device (:mod:`.joystick` reads its ``js_event`` records, :mod:`.gamepad` maps axes and buttons with a
TOML mapping file), what a key or button asks of the vehicle (:mod:`.actions`), the sticks as
``manual_control_setpoint`` (:mod:`.sticks`) and the screen (:mod:`.screen`). The terminal, the device and the
bus are :mod:`stack.cli.teleop`'s.
"""
