"""The ``mavlink`` module: the stack as a PX4 autopilot that ground stations and SDKs connect to."""
