"""The message catalogue: msgspec Structs named after PX4's uORB topics, with PX4's fields and units."""
