"""stack: a PX4-shaped multicopter autopilot in Python, one process per module, uORB over Zenoh."""

__version__ = "0.1.0"
