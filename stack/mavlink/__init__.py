"""PX4's mavlink module and the MAVLink it speaks: links, framing, signing, PX4's modes, the protocols."""
