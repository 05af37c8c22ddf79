"""Which topics a recording, replay or export takes: ``sensor_gyro`` (every instance) or ``sensor_gyro/1``."""

from __future__ import annotations

from collections.abc import Iterable


class TopicSelection:
    """A set of topics, each either every instance (``name``) or one instance (``name/instance``).

    An empty selection selects everything.
    """

    __slots__ = ("instances", "names")

    def __init__(self, items: Iterable[str] = ()) -> None:
        self.names: set[str] = set()
        self.instances: set[tuple[str, int]] = set()
        for item in items:
            for part in item.split(","):
                part = part.strip()
                if not part:
                    continue
                name, sep, instance = part.partition("/")
                if sep:
                    if not instance.isdigit():
                        raise ValueError(f"'{part}' is not a topic or topic/instance (e.g. sensor_gyro/1)")
                    self.instances.add((name, int(instance)))
                else:
                    self.names.add(name)

    @property
    def everything(self) -> bool:
        return not self.names and not self.instances

    def __contains__(self, topic_instance: tuple[str, int]) -> bool:
        if self.everything:
            return True
        return topic_instance[0] in self.names or topic_instance in self.instances

    def missing_from(self, present: Iterable[tuple[str, int]]) -> list[str]:
        """Selected topics that do not occur in ``present`` (to warn about typos)."""
        present = set(present)
        names = {t for t, _ in present}
        missing = sorted(n for n in self.names if n not in names)
        missing += sorted(f"{t}/{i}" for t, i in self.instances if (t, i) not in present)
        return missing
