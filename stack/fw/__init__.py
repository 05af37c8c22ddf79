"""Fixed-wing control: attitude, TECS, L1/NPFG guidance, takeoff and landing, the navigator."""
