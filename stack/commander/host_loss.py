"""The commander's view of the vehicle's other hosts: which are lost, and when the flight is not its to judge.

A vehicle over several machines (a companion computer, a simulator machine, a ground laptop) loses a host when its
beats stop (:mod:`stack.bus.host_beats`). PX4 runs on one board and has no such loss; the nearest is a Pixhawk
whose companion goes silent (``src/modules/commander/Commander.cpp``, Offboard loss) or a companion that loses its
Pixhawk. The commander acts as the surviving side of that pair:

* a lost host is named, with its modules, in ``vehicle_status.lost_hosts``, the log and STATUSTEXT;
* a host that carries only links and observers (a ground laptop: MAVLink, recorder, plots) is only named: the
  data-link-loss failsafe (NAV_DLL_ACT) answers for the ground station it carried;
* while a host that carries flight modules (the plant, estimators, controllers) is late or lost, and for
  RETURN_GRACE_US after it is back (longer, up to CONVERGE_LIMIT_US, while the estimates are still invalid: an
  estimator started again converges first), the estimate and control-chain checks are *held*: their inputs went with
  the host, and the plant's side flies the vehicle on its own (the simulator and a Pixhawk land on Offboard loss).
  Flight termination on what a lost host took away would cut the motors the moment the host returns; PX4 likewise
  terminates only on a failure of its own board;
* a flight host that still beats but from which no output of the control chain has arrived for LATE_US (its link
  stalled: its router's messages held up behind others while its own beats pass) holds the checks too, as a late
  host does, for at most CONVERGE_LIMIT_US after its last output: the commander cannot tell its estimates' silence
  from the link's, and a termination on it would cut the motors of a vehicle whose estimators fly on the other
  side (if they truly hung, the rate loop starves of them, the motor commands stop and the plant's own failsafe
  lands);
* a module of another flight host whose liveliness ends may have gone with its whole host: a killed host's links
  close at once, before its beats are late. The checks are held DEATH_GRACE_US, until its host would be late;
  if the host still beats, the module alone died and the chain check acts on it then;
* once such a host is lost the failsafe lands (``host_loss``; cleared by a mode change or disarm, as PX4's
  position-loss landing is), so the vehicle keeps landing when the host comes back and can be armed again on the
  ground.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping, Sequence

from stack.bus.host_beats import BEAT_PERIOD_S, LATE_US, HostWatch

RETURN_GRACE_US = 3_000_000
"""After a flight host is back, its modules have this long to deliver fresh estimates and outputs (a link that
comes back delivers what it held in bursts for a while, measured up to 2 s on a loaded machine)."""

CONVERGE_LIMIT_US = 15_000_000
"""After a flight host is back, how long the checks wait at most for valid estimates (a restarted attitude estimator
converges in a few seconds)."""

DEATH_GRACE_US = LATE_US + round(BEAT_PERIOD_S * 1e6)
"""How long after another flight host's module died the checks wait to learn whether its host went with it: the
host is late LATE_US after its last beat, at most a beat period before the death."""


class HostLoss:
    """See the module docstring. ``outside``: the vehicle's modules outside the flight (links, observers)."""

    def __init__(
        self, placement: Mapping[str, Sequence[str]], own: str, lease_ms: int, outside: Collection[str]
    ) -> None:
        self.watch = HostWatch(placement, own, lease_ms)
        flight = {h: frozenset(modules) - frozenset(outside) for h, modules in self.watch.placement.items()}
        self._flight_hosts = frozenset(h for h, modules in flight.items() if modules)
        self.remote_flight_hosts: dict[str, frozenset[str]] = {
            h: modules for h, modules in flight.items() if h != own and modules
        }
        """The other hosts carrying flight modules, with those modules."""
        self._remote_flight_modules = frozenset().union(*self.remote_flight_hosts.values())
        self.lost: list[str] = []
        """The lost hosts, in the profile's order."""
        self._held_until_us = 0
        self._converging_until_us = 0

    def beat(self, host: str, now_us: int, payload: bytes = b"") -> None:
        self.watch.beat(host, now_us, payload)

    def module_died(self, module: str, now_us: int) -> None:
        """``module``'s liveliness ended (see the module docstring)."""
        if module in self._remote_flight_modules:
            self._held_until_us = max(self._held_until_us, now_us + DEATH_GRACE_US)

    def update(self, now_us: int, outputs_heard_us: Mapping[str, int | None] | None = None) -> list[str]:
        """The events of this cycle (hosts lost and back). ``outputs_heard_us``: for each of
        :attr:`remote_flight_hosts`, the last arrival of an output of its modules (None: none yet)."""
        events = [change.describe() for change in self.watch.update(now_us)]
        self.lost = self.watch.lost
        for heard in (outputs_heard_us or {}).values():
            if heard is not None and LATE_US < now_us - heard < CONVERGE_LIMIT_US:
                held = min(now_us + RETURN_GRACE_US, heard + CONVERGE_LIMIT_US)
                self._held_until_us = max(self._held_until_us, held)
        if any(h in self._flight_hosts for h in self.watch.late(now_us)):
            self._held_until_us = now_us + RETURN_GRACE_US
            self._converging_until_us = now_us + CONVERGE_LIMIT_US
        return events

    @property
    def flight_host_lost(self) -> bool:
        """A lost host carries flight modules: the ``host_loss`` failsafe (land)."""
        return any(h in self._flight_hosts for h in self.lost)

    def holding(self, now_us: int, estimates_valid: bool) -> bool:
        """Whether the estimate and control-chain checks are held (see the module docstring)."""
        return now_us < self._held_until_us or (not estimates_valid and now_us < self._converging_until_us)
