"""The ACL and password files as the embedded broker reads them (no broker): Mosquitto's
syntax, its matching and its hashes; bad lines refused naming the file and line."""

from __future__ import annotations

import base64
import hashlib
import stat
from pathlib import Path

import pytest

from mdm_ground.broker.accounts import create_accounts
from mdm_ground.broker.acl_file import Access, AclFileError, read_acl, topic_matches
from mdm_ground.broker.embedded import PROJECT_ACL
from mdm_ground.broker.password_file import (
    PasswordFileError,
    hash_password,
    read_passwords,
    verify,
)

R, W = Access.READ, Access.WRITE


@pytest.mark.parametrize(
    ("topic_filter", "topic", "expected"),
    [
        ("mdm/+/uav0/cmd", "mdm/m/uav0/cmd", True),
        ("mdm/+/uav0/cmd", "mdm/m/uav1/cmd", False),
        ("mdm/#", "mdm", True),
        ("mdm/#", "mdm/a/b/c", True),
        ("mdm/+", "mdm/a/b", False),
        ("#", "$SYS/x", False),
        ("+/x", "$SYS/x", False),
        ("$SYS/#", "$SYS/x", True),
        ("a/b", "a/b/c", False),
    ],
)
def test_topic_matching_follows_mqtt_4_7(topic_filter: str, topic: str, expected: bool) -> None:
    assert topic_matches(topic_filter, topic) is expected


def test_the_projects_acl_lets_each_account_do_its_part_alone() -> None:
    rules = read_acl(PROJECT_ACL)
    allows = rules.allows
    assert allows("uav0", "c", "mdm/m/uav0/state", W)
    assert not allows("uav0", "c", "mdm/m/uav1/state", W)
    assert not allows("uav0", "c", "mdm/m/uav0/cmd", W)
    assert allows("uav0", "c", "mdm/m/all/cmd", R)
    assert not allows("uav0", "c", "mdm/m/uav1/cmd", R)
    assert allows("uav3", "c", "mdm/m/uav3/detections", R | W)
    assert allows("operator", "c", "mdm/m/uav7/cmd", W)
    assert allows("operator", "c", "mdm/m/all/cmd", W)
    assert not allows("operator", "c", "mdm/m/uav0/state", W)
    assert allows("monitor", "c", "mdm/m/uav0/state", R)
    assert not allows("monitor", "c", "mdm/m/uav0/cmd", W)
    assert not allows(None, "c", "mdm/m/uav0/state", R)
    # a user name with a wildcard does not widen the pattern to every vehicle
    assert not allows("uav+", "c", "mdm/m/uav+/state", W)
    assert not allows("+", "c", "mdm/m/uav0/cmd", R)


def test_deny_wins_over_a_grant_and_client_ids_fill_patterns(tmp_path: Path) -> None:
    acl = tmp_path / "acl"
    acl.write_text(
        "# anonymous\ntopic read public/#\n\nuser alice\ntopic a/#\ntopic deny a/secret\n"
        "pattern write clients/%c/out\n"
    )
    rules = read_acl(acl)
    assert rules.allows(None, "x", "public/news", R)
    assert not rules.allows(None, "x", "public/news", W)
    assert rules.allows("alice", "x", "a/b", R | W)
    assert not rules.allows("alice", "x", "a/secret", R)
    assert rules.allows("bob", "dev1", "clients/dev1/out", W)
    assert not rules.allows("bob", "dev1", "clients/dev2/out", W)
    assert not rules.allows("bob", "dev+", "clients/dev+/out", W)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("user\n", "line 1: 'user' without a name"),
        ("# c\ntopic read\n", "line 2: 'topic' without a topic"),
        ("topics read a\n", "line 1: 'topics': expected 'user NAME'"),
    ],
)
def test_a_bad_acl_line_is_named(tmp_path: Path, text: str, message: str) -> None:
    acl = tmp_path / "acl"
    acl.write_text(text)
    with pytest.raises(AclFileError, match=message):
        read_acl(acl)


def test_hashes_verify_as_mosquitto_makes_them() -> None:
    stored = hash_password("s3cret", salt=b"0123456789ab")
    assert stored.startswith("$7$101$")
    assert verify("s3cret", stored)
    assert not verify("s3cret!", stored)
    salt = b"salty"
    old = hashlib.sha512(b"pw" + salt).digest()
    legacy = f"$6${base64.b64encode(salt).decode()}${base64.b64encode(old).decode()}"
    assert verify("pw", legacy)
    assert not verify("pw2", legacy)
    assert not verify("pw", "$7$101$not base64!$x")
    assert not verify("pw", "plain")


def test_a_malformed_password_line_is_named(tmp_path: Path) -> None:
    path = tmp_path / "passwd"
    path.write_text(f"a:{hash_password('x')}\nb:plaintext\n")
    with pytest.raises(PasswordFileError, match="line 2: expected USER:"):
        read_passwords(path)


def test_a_teams_accounts_are_private_and_verify(tmp_path: Path) -> None:
    acc = create_accounts(tmp_path / "acc", vehicles=3)
    stored = read_passwords(acc.passwd)
    assert sorted(stored) == ["monitor", "operator", "uav0", "uav1", "uav2"]
    assert all(verify(acc.password(n), stored[n]) for n in stored)
    assert len({acc.password(n) for n in stored}) == 5
    for path in [acc.folder, acc.passwd, acc.password_file("uav0")]:
        assert stat.S_IMODE(path.stat().st_mode) & 0o077 == 0, path
