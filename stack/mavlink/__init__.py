"""MAVLink: the link to an external autopilot (a Pixhawk running PX4), its codec mapping and PX4's modes."""
