"""The commander's logic: arming, flight modes, commands, failsafes, land detection, and the simulated
battery (pure classes; the module glue lives in ``module.py`` and ``land_module.py``)."""
