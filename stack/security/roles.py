"""What an identity of a keystore may do on the bus (stack.security.keystore)."""

ROLES = ("host", "operator", "observer")
"""``host``: the modules and links a host of the profile runs; ``operator``: a person or script who may command;
``observer``: one who may only read."""
