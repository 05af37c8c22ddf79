"""Vehicle models as data (mass, inertia, rotors, surfaces), read by the simulator, the allocator and controllers."""
