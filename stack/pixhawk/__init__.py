"""The `pixhawk` plant: a PX4 Pixhawk over MAVLink in the simulator's place, its messages mapped to the stack's."""
