"""A terminal's bytes → keys: characters, arrows in both cursor modes, sequences split between reads, a lone Esc."""

from stack.teleop.keys import KeyDecoder


def test_characters_control_characters_and_arrows():
    d = KeyDecoder()
    assert d.feed(b"w\x1b[A\x1b[B\x1b[C\x1b[Dq\x03") == ["w", "up", "down", "right", "left", "q", "\x03"]
    assert not d.pending


def test_application_cursor_mode_and_modified_arrows():
    assert KeyDecoder().feed(b"\x1bOA\x1bOD\x1b[1;5C") == ["up", "left", "right"]


def test_a_sequence_split_between_reads_is_kept_until_it_ends():
    d = KeyDecoder()
    assert d.feed(b"a\x1b") == ["a"]
    assert d.pending
    assert d.feed(b"[") == []
    assert d.feed(b"A") == ["up"]
    assert not d.pending


def test_a_lone_esc_is_the_esc_key_once_nothing_follows():
    d = KeyDecoder()
    assert d.feed(b"\x1b") == []
    assert d.flush() == ["esc"]
    assert d.flush() == []
    assert d.feed(b"\x1bw") == ["esc", "w"]  # Alt-w: Esc, then w


def test_other_sequences_and_non_ascii_bytes_are_dropped():
    assert KeyDecoder().feed(b"\x1b[15~x\xc3\xa9y\x1b[<0;12;40M") == ["x", "y"]  # F5, é in UTF-8, a mouse report


def test_a_sequence_cut_by_a_control_character_ends_there():
    assert KeyDecoder().feed(b"\x1b[12\x03w") == ["\x03", "w"]
