"""The accounts of one team on the embedded broker: one per vehicle (``uav0``, ``uav1``, ...,
named like its topic level, as docker/mosquitto's ACL wants), ``operator`` (the page: it alone
may command) and ``monitor`` (read only), each with a fresh random password."""

from __future__ import annotations

import os
import secrets
from dataclasses import dataclass
from pathlib import Path

from mdm_ground.broker.password_file import write_passwords

PASSWD = "passwd"
"""The Mosquitto password file the broker reads, in the accounts folder."""


@dataclass(frozen=True)
class Accounts:
    """A folder holding ``passwd`` (the hashes) and ``NAME.pw`` (each password in clear, for
    the client of that account: ``--mqtt-password-file``), readable by its owner alone."""

    folder: Path
    vehicles: int

    @property
    def passwd(self) -> Path:
        return self.folder / PASSWD

    def password_file(self, account: str) -> Path:
        """``NAME.pw``; ``uav{vehicle}.pw`` gives the template `companion run` fills."""
        return self.folder / f"{account}.pw"

    def password(self, account: str) -> str:
        return self.password_file(account).read_text(encoding="utf-8").strip()

    def names(self) -> list[str]:
        return [*(f"uav{i}" for i in range(self.vehicles)), "operator", "monitor"]


def create_accounts(folder: Path, vehicles: int) -> Accounts:
    """Fresh accounts for a team of ``vehicles`` in ``folder`` (made, mode 700; files there
    already are replaced)."""
    folder.mkdir(parents=True, exist_ok=True, mode=0o700)
    folder.chmod(0o700)
    accounts = Accounts(folder, vehicles)
    passwords = {name: secrets.token_hex(16) for name in accounts.names()}
    for name, password in passwords.items():
        fd = os.open(accounts.password_file(name), os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(password + "\n")
    write_passwords(accounts.passwd, passwords)
    return accounts
