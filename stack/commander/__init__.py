"""The commander's logic: arming, flight modes, commands, failsafes, Offboard checks and land detection (pure
classes; the module glue lives in ``module.py``)."""
