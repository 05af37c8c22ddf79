"""``stack keys``: the keystore that admits members to a bus spread over machines (stack.security.keystore, imported
by each command: cryptography costs every other command of the CLI nothing)."""

from __future__ import annotations

import datetime
import json
from pathlib import Path

import typer

from stack.cli.common import command_group, fail, print_table
from stack.security.roles import ROLES

app = command_group(help="Keystore: a certificate authority and the identities of hosts, operators and observers")


@app.command("init")
def init(directory: Path = typer.Argument(..., help="Where the keystore goes (created)")) -> None:
    """Make a certificate authority in DIRECTORY: ca.pem (give it to every member) and ca.key (keep it there)."""
    from stack.security.keystore import KeystoreError, init_keystore

    try:
        cert = init_keystore(directory)
    except KeystoreError as e:
        fail(str(e), code=2)
    typer.echo(f"keystore {directory}: authority {cert}")


@app.command("issue")
def issue(
    directory: Path = typer.Argument(..., help="The keystore"),
    name: str = typer.Argument(..., help="The identity: a host of the profile ([hosts.NAME]), a person or a script"),
    role: str = typer.Option(..., "--role", help=f"What it may do: {', '.join(ROLES)}"),
    address: list[str] = typer.Option(
        [], "--address", help="A host name or IP address it is reached at (again for more); loopback is always in"
    ),
    days: int = typer.Option(365, "--days", min=1, help="Days it is valid"),
) -> None:
    """Issue an identity: identities/NAME.pem and NAME.key (owner-only), signed by the keystore's authority."""
    from stack.security.keystore import KeystoreError, issue_identity

    try:
        identity = issue_identity(directory, name, role, tuple(address), days)
    except (KeystoreError, ValueError) as e:
        fail(str(e), code=2)
    until = f"{identity.not_after:%Y-%m-%d}"
    typer.echo(f"{identity.name} ({identity.role}) until {until}: {identity.cert}, {identity.key}")


@app.command("list")
def list_(
    directory: Path = typer.Argument(..., help="The keystore"),
    as_json: bool = typer.Option(False, "--json", help="As JSON"),
) -> None:
    """The identities of a keystore: name, role, expiry, and the names and addresses each is valid for."""
    from stack.security.keystore import KeystoreError, list_identities

    try:
        identities = list_identities(directory)
    except KeystoreError as e:
        fail(str(e), code=2)
    now = datetime.datetime.now(datetime.UTC)
    if as_json:
        rows = [
            {"name": i.name, "role": i.role, "expires": i.not_after.isoformat(), "expired": i.expired(now),
             "valid_for": list(i.names)}
            for i in identities
        ]  # fmt: skip
        typer.echo(json.dumps(rows, indent=2))
        return
    print_table(
        ("NAME", "ROLE", "EXPIRES", "VALID FOR"),
        [
            (i.name, i.role, f"{i.not_after:%Y-%m-%d}" + (" (expired)" if i.expired(now) else ""), ", ".join(i.names))
            for i in identities
        ],
    )
