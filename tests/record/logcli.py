"""``stack log`` and ``stack replay`` as the root CLI mounts them, runnable before they are mounted.

``python -m tests.record.logcli log info FILE`` / ``... replay FILE``.
"""

import typer

from stack.cli import log

app = typer.Typer(add_completion=False)
app.add_typer(log.app, name="log")
app.command("replay")(log.replay)

if __name__ == "__main__":
    app()
