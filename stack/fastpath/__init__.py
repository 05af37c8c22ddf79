"""The same-host lockstep fast path: lockstep topics through shared memory, one eventfd per process.

In a lockstep run started by one supervisor, the messages lockstep members exchange do not travel
over Zenoh. The supervisor creates one anonymous shared-memory file (``memfd_create``) and one
``eventfd`` per module, and every module process inherits them (so nothing is ever left in
``/dev/shm`` or on disk, whatever kills the processes). In that region:

- each module owns a *slot*: its name, pid, role, trigger, the topics it publishes and subscribes,
  and counters only it writes (runs started and finished, messages published per topic, trigger
  messages consumed per publisher);
- each (publisher, topic) has a ring of fixed-size records (index, simulated time, publisher
  sequence number, length, msgpack payload), written only by its publisher;
- the coordinator (the simulator) writes the simulated time, the ticks of timed members, and which
  processes are admitted to the run.

A publisher writes its record and then wakes, through their eventfds, exactly the members its topic
triggers. A member runs once per trigger record (or tick) and reads the newest record of each other
input that is visible at its time (:mod:`stack.runtime.inputs` gives the rules). When a member has no
work left and everything it triggered has finished, it wakes the coordinator, which checks on a
consistent snapshot of the counters that every run of the step has finished before it advances time.
Waiting uses ``poll()`` on the eventfd plus, in the coordinator, the members' pidfds, so a member that
dies is noticed within milliseconds. Modules sharing a process (a profile's ``process = "NAME"``) keep a
slot each; one thread serves them, running a member another of them woke without an eventfd
(:class:`stack.runtime.fastrun.ProcessGroup`).

A member a profile gives ``transport = "zenoh"`` (as a module on another host must) keeps a slot too, which
the coordinator's process serves for it over Zenoh (:mod:`stack.fastpath.bridge`): one run, both transports.

A topic is also put on Zenoh while something outside the fast path subscribes to it (the supervisor
watches the topic graph and sets a flag per publication), so ``stack topic``, ground stations and
modules on other hosts see every topic as before; messages from outside the run (a CLI command)
still arrive over Zenoh and are seen at once.
"""
