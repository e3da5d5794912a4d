"""What can be checked of docker/ without a Docker engine (test_compose_emulator.py runs it on
one): every command in the compose files, with the defaults of its ${VAR:-default} settings, is
an entry point of the package whose real argparse parser accepts its flags, every file they
name exists (or is a secret kept out of git and the image), and the image runs as non-root."""

from __future__ import annotations

import fnmatch
import importlib
import re
import tomllib
from pathlib import Path
from typing import Any

import pytest
import yaml

from mdm_ground.fleet.sitl_team import companion_link
from mdm_profiles import load_profile

ROOT = Path(__file__).resolve().parents[2]
DOCKER = ROOT / "docker"
COMPOSE_FILES = ("compose.yaml", "compose.sitl.yaml")
SCRIPTS: dict[str, str] = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]


def _compose(name: str) -> dict[str, Any]:
    """The compose file as `docker compose` reads it with none of its variables set."""
    text = (DOCKER / name).read_text()
    assert not re.search(r"\$\{\w+\}", text), "a setting without a default"
    data: dict[str, Any] = yaml.safe_load(re.sub(r"\$\{\w+:-([^}]*)\}", r"\1", text))
    return data


def _ours(compose: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """Services running the mdm-search image (not the broker)."""
    return {k: s for k, s in compose["services"].items() if s.get("image") == "mdm-search:latest"}


def _dockerfile() -> list[str]:
    """Instructions of docker/Dockerfile with continuation lines joined, comments dropped."""
    text = re.sub(r"\\\n\s*", " ", (DOCKER / "Dockerfile").read_text())
    return [line.strip() for line in text.splitlines() if line.strip() and line[0] != "#"]


def _copies() -> dict[str, str]:
    """Image path -> repository path of every COPY from the build context."""
    out = {}
    for line in _dockerfile():
        parts = line.split()
        if parts[0] == "COPY" and not parts[1].startswith("--from"):
            for src in parts[1:-1]:
                out[parts[-1].rstrip("/")] = src
    return out


def _in_repo(image_path: str) -> Path | None:
    """The repository file an absolute image path was copied from, if it was."""
    for dest, src in _copies().items():
        if dest.startswith("/") and (image_path == dest or image_path.startswith(dest + "/")):
            return ROOT / src / image_path[len(dest) :].lstrip("/")
    return None


def _parse(argv: list[str]) -> Any:
    """argv[0] must be a [project.scripts] entry; its module's real parser parses the rest."""
    assert argv[0] in SCRIPTS, f"{argv[0]!r} is not an entry point: {sorted(SCRIPTS)}"
    module_name, func = SCRIPTS[argv[0]].split(":")
    module = importlib.import_module(module_name)
    assert callable(getattr(module, func))
    try:
        return module.build_parser().parse_args(argv[1:])
    except SystemExit:
        pytest.fail(f"{argv[0]} rejects its compose arguments {argv[1:]}")


def _profile_ref(ref: str) -> str:
    if ref.startswith("/"):
        path = _in_repo(ref)
        assert path is not None, f"profile {ref} is not copied into the image"
        return str(path)
    return ref


def _ignored(path: str, ignore_file: Path) -> bool:
    patterns = [p.strip().rstrip("/") for p in ignore_file.read_text().splitlines()]
    return any(p and not p.startswith("#") and fnmatch.fnmatch(path, p) for p in patterns)


@pytest.mark.parametrize("name", COMPOSE_FILES)
def test_every_command_is_an_entry_point_whose_parser_accepts_it(name: str) -> None:
    compose = _compose(name)
    services = _ours(compose)
    assert services
    for svc_name, svc in services.items():
        args = _parse(svc["command"])
        load_profile(_profile_ref(args.profile))  # the profile exists in the image and loads
        mounted = {f"/run/secrets/{s}" for s in svc.get("secrets", [])}
        for flag in ("signing_key_file", "mqtt_password_file"):
            path = getattr(args, flag, None)
            if path is not None:
                assert str(path) in mounted, f"{svc_name}: {flag} {path} is not a mounted secret"
        for secret in svc.get("secrets", []):
            assert secret in compose["secrets"], f"{svc_name}: undeclared secret {secret}"


@pytest.mark.parametrize("name", COMPOSE_FILES)
def test_files_named_by_compose_exist_and_secrets_stay_out_of_git_and_image(name: str) -> None:
    compose = _compose(name)
    for svc in compose["services"].values():
        build = svc.get("build")
        if build is not None:
            context = (DOCKER / build["context"]).resolve()
            assert context == ROOT
            assert (context / build["dockerfile"]).is_file()
        for volume in svc.get("volumes", []):
            source = volume.split(":")[0]
            if source.startswith("."):
                assert (DOCKER / source).exists(), f"bind mount {source} missing"
    for secret in compose["secrets"].values():
        path = (DOCKER / secret["file"]).resolve().relative_to(ROOT)
        assert path.parts[0] == "secrets"
        assert _ignored("secrets", ROOT / ".gitignore")
        assert _ignored("secrets", ROOT / ".dockerignore")


def test_emulator_compose_runs_broker_emulator_and_three_distinct_signed_companions() -> None:
    compose = _compose("compose.yaml")
    services = _ours(compose)
    emulators = [s for s in services.values() if s["command"][0] == "sim-vehicle"]
    assert len(emulators) == 1
    emulator = _parse(emulators[0]["command"])
    assert emulator.signing_key_file is not None
    companions = {k: _parse(s["command"]) for k, s in services.items() if k.startswith("companion")}
    assert sorted(a.vehicle for a in companions.values()) == list(range(3))
    assert emulator.vehicles == len(companions)
    for args in companions.values():
        assert args.signing_key_file == emulator.signing_key_file
        assert args.connect is None  # default udpin:0.0.0.0:14540+i, where the emulator sends
        assert args.base_port == emulator.base_port
        assert args.mqtt == "127.0.0.1"  # the broker's namespace, which they share
    for svc in services.values():
        assert svc["network_mode"] == "service:mosquitto"
    broker = compose["services"]["mosquitto"]
    assert broker["image"].startswith("eclipse-mosquitto:")
    assert "./mosquitto:/mosquitto/config:ro" in broker["volumes"]
    assert all(p.startswith("127.0.0.1:") for p in broker["ports"]), "published beyond loopback"
    conf = (DOCKER / "mosquitto" / "mosquitto.conf").read_text()
    secret = re.search(r"^password_file /run/secrets/(\w+)$", conf, re.MULTILINE)
    assert secret is not None
    assert secret.group(1) in broker["secrets"]


def test_sitl_compose_points_companion_i_at_udp_14540_plus_i_without_an_emulator() -> None:
    services = _ours(_compose("compose.sitl.yaml"))
    assert all(s["command"][0] != "sim-vehicle" for s in services.values())
    for svc in services.values():
        args = _parse(svc["command"])
        assert args.connect == f"udpin:0.0.0.0:{14540 + args.vehicle}"
        assert svc["network_mode"] == "host"


def test_dockerfile_slim_base_installs_every_package_and_runs_as_non_root() -> None:
    lines = _dockerfile()
    base = next(line for line in lines if line.startswith("ARG BASE="))
    assert re.fullmatch(r"ARG BASE=python:3\.1[12]-slim", base), base
    stages = [line.split() for line in lines if line.startswith("FROM")]
    named = {s[3] for s in stages if len(s) == 4 and s[2] == "AS"}
    assert all(s[1] in ("${BASE}", *named) for s in stages), "a stage from another base"
    final = lines[max(i for i, line in enumerate(lines) if line.startswith("FROM")) :]
    users = [line.split()[1] for line in final if line.startswith("USER")]
    assert users
    assert users[-1] not in ("root", "0")
    assert any("useradd" in line and users[-1] in line for line in final)
    assert not any(line.startswith(("RUN", "ARG PIP")) and "pip" in line for line in final), (
        "pip runs in the final stage"
    )
    assert any(line.startswith("COPY --from=build") for line in final)
    copies = _copies()
    for src in copies.values():
        assert (ROOT / src).exists(), f"COPY source {src} missing"
    include = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"][
        "packages"
    ]["find"]["include"]
    packages = {p.rstrip("*") for p in include}
    assert packages <= {Path(src).name for src in copies.values()}, "a package is not copied"
    for must in (".git", ".venv", "secrets"):
        assert _ignored(must, ROOT / ".dockerignore"), must


def test_arducopter_env_file_names_serial0_of_instance_i_for_companion_i() -> None:
    lines = (DOCKER / "sitl-arducopter.env").read_text().splitlines()
    settings = dict(line.split("=", 1) for line in lines if line and not line.startswith("#"))
    services = _ours(_compose("compose.sitl.yaml"))
    assert len(settings) == len(services)
    for i in range(len(services)):
        assert settings[f"MDM_CONNECT_{i}"] == companion_link("arducopter", i)
