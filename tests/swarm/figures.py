"""What a swarm flight of two vehicles of the default profile gives on one seed, however it is flown (every module
its own process or each vehicle's in one, on one machine or spread over two): a seed is one swarm flight."""

FORMATION_SEED = 3
FORMATION_METRICS = {
    "formation_error_rms_m": 0.1706807743236857,
    "formation_error_max_m": 0.3410481185866423,
    "min_separation_m": 4.7202086739577345,
    "all_landed_and_disarmed": True,
    "box_time_s": 48.0,
}
"""`stack fly swarm_formation --vehicles 2 --seed 3`: on one machine, grouped or not, and over two hosts (taken on
another CPU than an AMD EPYC, which gives them within 2e-13, relative)."""
