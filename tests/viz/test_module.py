"""rerun_bridge pieces that need no stack: rotor geometry from a parameter service, lazy Rerun import."""

import subprocess
import sys

import pytest
import zenoh

from stack.bus.config import BusConfig
from stack.mixer import effectiveness
from stack.params.store import ParamStore
from stack.runtime.services import ParamService
from stack.viz.module import query_rotors


def test_rotor_geometry_is_read_from_whichever_module_serves_ca_rotor_parameters():
    hexa = {"CA_ROTOR_COUNT": 6}
    for i in range(6):
        hexa |= {f"CA_ROTOR{i}_PX": 0.1 * i, f"CA_ROTOR{i}_PY": -0.1 * i, f"CA_ROTOR{i}_PZ": 0.0}
    session = zenoh.open(BusConfig().zenoh_config("test"))
    try:
        assert query_rotors(session, "t9") is None
        other = ParamService(session, "t9", "other", ParamStore(()))
        allocator = ParamService(session, "t9", "allocator", ParamStore(effectiveness.PARAMS, hexa))
        try:
            rotors = query_rotors(session, "t9")
        finally:
            allocator.close()
            other.close()
    finally:
        session.close()
    assert rotors is not None and len(rotors) == 6
    assert rotors[3] == pytest.approx((0.3, -0.3, 0.0))


def test_declaring_the_module_does_not_import_rerun():
    code = "import sys, stack.viz.module, stack.cli.plot, stack.viz.export; print('rerun' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
