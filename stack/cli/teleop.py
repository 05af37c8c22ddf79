"""``stack teleop``: fly by keyboard in a plain terminal, or by a gamepad on the Linux joystick device.

The terminal is put in cbreak mode (keys arrive as pressed, unechoed; Ctrl-C is still SIGINT, Ctrl-Z is turned
off: a suspended stick source would leave the vehicle with its last sticks until the failsafe) on the alternate
screen, and given back as it was however teleop ends: a key, Ctrl-C, end of input, a signal or an error. The
sticks go out as ``manual_control_setpoint`` at RATE_HZ whatever the keys do, so the commander's
manual-control-loss failsafe (COM_RC_LOSS_T) means what it says; on the way out one last setpoint with the
sticks centred (:func:`stack.teleop.sticks.parting`), then nothing, and the failsafe takes over. A gamepad lost
(unplugged) stops the sticks at once and is looked for again every REOPEN_S. Arm, disarm and modes are
``vehicle_command`` as ``stack cmd`` sends them, answered on the screen without waiting.
"""

from __future__ import annotations

import collections
import contextlib
import errno
import os
import select
import shutil
import signal
import sys
import termios
import time
import tty
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import typer
import zenoh

from stack.attctl import rotors_joy
from stack.bus.node import Node
from stack.cli import vehicle_summary
from stack.cli.cmd import NO_COMMANDER, answers, clock_of, from_ground_station, outcome, vehicle_params
from stack.cli.common import EndpointOption, VehicleOption, connect, fail, wait_until_sent
from stack.msg.system import VehicleStatus
from stack.teleop import actions
from stack.teleop.gamepad import DEFAULT_MAPPING, Gamepad, Mapping, MappingError, load_mapping
from stack.teleop.joystick import JsDecoder
from stack.teleop.keyboard import QUIT, Keyboard
from stack.teleop.keys import KeyDecoder
from stack.teleop.screen import Frame, gamepad_keys, keyboard_keys, render
from stack.teleop.sticks import Sticks, parting, setpoint

RATE_HZ = 50.0
DRAW_S = 0.1
ESC_WAIT_S = 0.05
"""An Esc with nothing after it for this long was the Esc key, not the start of an arrow's sequence."""
ACK_WAIT_S = 3.0
REOPEN_S = 1.0
SAID_LINES = 3
FLUSH_S = 0.1
"""Time Zenoh gets to send the last setpoint before the session closes."""
ENTER_SCREEN = "\x1b[?1049h\x1b[?25l"  # alternate screen, cursor hidden
LEAVE_SCREEN = "\x1b[?25h\x1b[?1049l"
HINTS = {errno.EACCES: " (is your user in the 'input' group?)", errno.ENOENT: " (is the gamepad plugged in?)"}
STOP_SIGNALS = (signal.SIGTERM, signal.SIGHUP, signal.SIGQUIT)


class _Stopped(Exception):
    def __init__(self, signum: int) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


def teleop(
    joystick: Path | None = typer.Option(
        None, "--joystick", "-j", help="Fly by this gamepad (a Linux joystick device, e.g. /dev/input/js0)"
    ),
    mapping: Path | None = typer.Option(
        None, "--mapping", "-m", help="The gamepad's mapping file (TOML; default: an Xbox-layout pad)"
    ),
    vehicle: str | None = VehicleOption,
    endpoint: str | None = EndpointOption,
) -> None:
    """Fly by keyboard (arrows pitch and roll, a/d yaw, w/s throttle; keys to arm and switch modes) or by a
    gamepad, with the vehicle's state on the screen. Fly a real-time stack (`stack up --realtime`)."""
    if mapping is not None and joystick is None:
        fail("--mapping is the mapping of a --joystick; give both", code=2)
    pad = None
    if joystick is not None:
        try:
            pad = _Device(joystick, load_mapping(mapping or DEFAULT_MAPPING))
        except MappingError as e:
            fail(str(e), code=2)
        except OSError as e:
            fail(f"cannot open the joystick {joystick}: {e.strerror}{HINTS.get(e.errno or 0, '')}", code=2)
    keyboard = sys.stdin.isatty()
    if not keyboard and pad is None:
        fail("stack teleop reads the keyboard of a terminal: run it in one, or give --joystick", code=2)
    try:
        with connect(vehicle, endpoint, name="teleop") as node:
            link = _Link(node, pad)
            try:
                with _terminal(keyboard):
                    why = link.run(keyboard)
            finally:
                link.part()
    except _Stopped as e:
        typer.echo(f"teleop: stopped by {e}", err=True)
        raise typer.Exit(128 + e.signum) from None
    except KeyboardInterrupt:
        typer.echo("teleop: stopped by Ctrl-C", err=True)
        raise typer.Exit(130) from None
    finally:
        if pad is not None:
            pad.close()
    typer.echo(link.report(why))


@contextlib.contextmanager
def _terminal(keyboard: bool) -> Iterator[None]:
    """cbreak mode (with a keyboard) and the alternate screen, given back on the way out; the stop signals
    raise _Stopped so that the way out is taken."""

    def stop(signum: int, _frame: Any) -> None:
        raise _Stopped(signum)

    previous = {s: signal.signal(s, stop) for s in STOP_SIGNALS}
    # Ctrl-C quits even when teleop was started with SIGINT ignored (a child inherits SIG_IGN across exec).
    previous[signal.SIGINT] = signal.signal(signal.SIGINT, signal.default_int_handler)
    fd = sys.stdin.fileno()
    saved = termios.tcgetattr(fd) if keyboard else None
    try:
        if saved is not None:
            tty.setcbreak(fd)
            attrs = termios.tcgetattr(fd)
            attrs[6][termios.VSUSP] = b"\x00"  # _POSIX_VDISABLE
            termios.tcsetattr(fd, termios.TCSANOW, attrs)
        sys.stdout.write(ENTER_SCREEN)
        sys.stdout.flush()
        yield
    finally:
        with contextlib.suppress(OSError, termios.error):  # a terminal hung up is given back to nobody
            sys.stdout.write(LEAVE_SCREEN)
            sys.stdout.flush()
            if saved is not None:
                termios.tcsetattr(fd, termios.TCSADRAIN, saved)
        for s, handler in previous.items():
            signal.signal(s, handler)


class _Device:
    """The gamepad: its device (None while lost), its decoder and its state."""

    def __init__(self, path: Path, mapping: Mapping) -> None:
        self.path = path
        self.mapping = mapping
        self.fd: int | None = None
        self.lost = ""
        self._retry_at = 0.0
        self._open()

    def _open(self) -> None:
        self.fd = os.open(self.path, os.O_RDONLY | os.O_NONBLOCK)
        self.decoder = JsDecoder()
        self.state = Gamepad(self.mapping)
        self.lost = ""
        self.ready = False
        """Whether the device has told its state since it was opened (the driver does at once)."""

    @property
    def sending(self) -> bool:
        return self.fd is not None and self.ready

    def status(self) -> str:
        if self.fd is None:
            return f"LOST: {self.lost}, looking for it again"
        return "" if self.ready else "waiting for its state"

    def read(self) -> list[str]:
        """Read what the device has; the actions of the buttons pressed."""
        assert self.fd is not None
        done: list[str] = []
        try:
            while data := os.read(self.fd, 4096):
                for event in self.decoder.feed(data):
                    self.ready = True
                    if (action := self.state.take(event)) is not None:
                        done.append(action)
        except BlockingIOError:
            return done
        except OSError as e:
            self._lose(e.strerror or str(e))
            return done
        self._lose("the device closed")
        return done

    def _lose(self, why: str) -> None:
        self.close()
        self.lost = why
        self._retry_at = time.monotonic() + REOPEN_S

    def retry(self, now: float) -> None:
        if self.fd is None and now >= self._retry_at:
            try:
                self._open()
            except OSError as e:
                self._lose(e.strerror or str(e))

    def close(self) -> None:
        if self.fd is not None:
            os.close(self.fd)
            self.fd = None


class _Link:
    """The session with the vehicle: the sticks out, commands out and their answers in, the vehicle's state in."""

    def __init__(self, node: Node, pad: _Device | None) -> None:
        self.node = node
        self.pad = pad
        self.keyboard = Keyboard()
        self.sticks = Sticks() if pad is None else pad.state.sticks()
        self._sticks_pub = node.publisher("manual_control_setpoint")
        self._command_pub = node.publisher("vehicle_command")
        watched = (*vehicle_summary.TOPICS, "vehicle_command_ack", "mavlink_log")
        self._subs = {topic: node.subscriber(topic, keep_last=True) for topic in watched}
        wait_until_sent(node, [(topic, 0) for topic in watched])
        self.clock = clock_of(node)
        self.rotors = rotors_joy.JoyMapping(vehicle_params(node, tuple(p.name for p in rotors_joy.PARAMS)))
        self.latest: dict[str, Any] = {}
        self.heard = time.monotonic()
        self.answer = ""
        self.said: collections.deque[str] = collections.deque(maxlen=SAID_LINES)
        self._awaiting: tuple[str, Any, float] | None = None
        self.commands = 0
        self._sent: collections.deque[float] = collections.deque()
        self.count = 0
        self.began = time.monotonic()

    def run(self, keyboard: bool) -> str:
        """Until a quit key or the end of the keyboard's input: the reason."""
        stdin = sys.stdin.fileno()
        keys = KeyDecoder()
        key_bytes_at = 0.0
        next_send = next_draw = time.monotonic()
        while True:
            fds = [stdin] if keyboard else []
            if self.pad is not None and self.pad.fd is not None:
                fds.append(self.pad.fd)
            wait = max(0.0, min(next_send, next_draw) - time.monotonic())
            readable = select.select(fds, [], [], wait)[0]
            now = time.monotonic()
            pressed: list[str] = []
            if stdin in readable:
                try:
                    data = os.read(stdin, 1024)
                except OSError:  # EIO: the terminal is gone
                    data = b""
                if not data:
                    return "end of input"
                pressed = keys.feed(data)
                key_bytes_at = now
            elif keys.pending and now - key_bytes_at > ESC_WAIT_S:
                pressed = keys.flush()
            for key in pressed:
                action = self.keyboard.key(key, now)
                if action == QUIT:
                    return "quit"
                if action is not None:
                    self.send(action, now)
            if self.pad is not None:
                if self.pad.fd in readable:
                    for action in self.pad.read():
                        self.send(action, now)
                self.pad.retry(now)
            if now >= next_send:
                self._publish_sticks(now)
                next_send += 1.0 / RATE_HZ  # a late one is made up for at once...
                if next_send < now - 1.0 / RATE_HZ:
                    next_send = now  # ...but not a stall's worth, in a burst
            self._poll(now)
            if now >= next_draw:
                self._draw(now)
                next_draw = now + DRAW_S

    def _sending(self) -> bool:
        return self.pad is None or self.pad.sending

    def _publish_sticks(self, now: float) -> None:
        if self.pad is not None:
            self.sticks = self.pad.state.sticks()
        else:
            self.sticks = self.keyboard.sticks(now)
        if self._sending():
            self._sticks_pub.publish(setpoint(self.sticks, self.node.now_us()))
            self.count += 1
            self._sent.append(now)
            while self._sent[0] < now - 1.0:
                self._sent.popleft()

    def part(self) -> None:
        """The last setpoint: sticks centred (:func:`parting`), then the commander's failsafe."""
        if not self._sending():
            return
        status = self.latest.get("vehicle_status")
        self.sticks = parting(self.sticks, status.nav_state if status is not None else None)
        with contextlib.suppress(zenoh.ZError):  # the way out goes on, whatever became of the bus
            self._sticks_pub.publish(setpoint(self.sticks, self.node.now_us()))
            self.count += 1
            time.sleep(FLUSH_S)

    def send(self, action: str, now: float) -> None:
        label, cmd = actions.command(action)
        self.commands += 1
        if not self._command_pub.matching():
            self.answer = f"{label}: {NO_COMMANDER}"
            return
        cmd = from_ground_station(cmd)
        self._command_pub.publish(cmd)
        self._awaiting = (label, cmd, now)
        self.answer = f"{label}: sent"

    def _poll(self, now: float) -> None:
        for topic, sub in self._subs.items():
            while (item := sub.poll()) is not None:
                msg = item.msg
                if topic == "vehicle_command_ack":
                    if self._awaiting is not None and answers(msg, self._awaiting[1]):
                        self.answer = outcome(self._awaiting[0], msg)
                        self._awaiting = None
                    continue
                if topic == "mavlink_log":
                    self.said.append(msg.text)
                self.latest[topic] = msg
                self.heard = now
        if self._awaiting is not None and now - self._awaiting[2] > ACK_WAIT_S:
            self.answer = f"{self._awaiting[0]}: no answer within {ACK_WAIT_S:g} s (is the commander running?)"
            self._awaiting = None

    def _frame(self, now: float) -> Frame:
        status = self.latest.get("vehicle_status")
        lpos = self.latest.get("vehicle_local_position")
        if self.pad is None:
            source = f"keyboard, stick limit {self.keyboard.limit * 100:.0f} %"
            keys = keyboard_keys()
        else:
            source = f"gamepad {self.pad.path}" + (f" {state}" if (state := self.pad.status()) else "")
            keys = gamepad_keys(self.pad.mapping)
        rotors = None
        if status is not None and status.nav_state == VehicleStatus.NAVIGATION_STATE_EXTERNAL1:
            rotors = self.rotors.command(*self.sticks)
        rate = (len(self._sent) - 1) / (self._sent[-1] - self._sent[0]) if len(self._sent) > 1 else 0.0
        return Frame(
            vehicle=self.node.vehicle,
            clock=self.clock,
            summary=vehicle_summary.summary(self.latest, None),
            velocity=(lpos.vx, lpos.vy, lpos.vz) if lpos is not None else None,
            sticks=self.sticks,
            source=source,
            sending=self._sending(),
            subscribed=self._sticks_pub.matching(),
            rate_hz=rate,
            silent_s=now - self.heard,
            keys=keys,
            answer=self.answer,
            commands=self.commands,
            said=list(self.said),
            rotors=rotors,
        )

    def _draw(self, now: float) -> None:
        width = shutil.get_terminal_size().columns
        lines = render(self._frame(now))
        sys.stdout.write("\x1b[H" + "".join(line[:width] + "\x1b[K\n" for line in lines) + "\x1b[J")
        sys.stdout.flush()

    def report(self, why: str) -> str:
        elapsed = time.monotonic() - self.began
        rate = self.count / max(elapsed, 1e-9)
        return f"teleop: {why}; {self.count} setpoints sent in {elapsed:.1f} s ({rate:.1f} Hz)"
