"""Small, fast math for control loops: 3-vectors and quaternions as tuples, scalar helpers, filters."""
