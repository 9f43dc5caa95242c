"""The systemd unit of ``dronewrapper install`` (pure rendering; systemd-analyze checks it in
tests/integration/test_install_unit.py)."""

from pathlib import Path

from dronewrapper_compose.jetson_wheels import (
    PLATFORMS,
    missing_wheel,
    parse_requirement,
    pip_resolve_argv,
    third_party_requirements,
    wheel_names,
)
from dronewrapper_compose.systemd_unit import (
    UnitSpec,
    device_unit,
    escape_name,
    render_unit,
    serial_devices,
    unit_name,
)


def test_names_are_escaped_as_systemd_escape_does():
    assert unit_name("compose/px4_real_follow_person.yaml") == (
        "dronewrapper-px4_real_follow_person.service"
    )
    assert device_unit("/dev/ttyUSB0") == "dev-ttyUSB0.device"
    assert device_unit("/dev/serial/by-id/usb-FTDI_X-if00") == (
        "dev-serial-by\\x2did-usb\\x2dFTDI_X\\x2dif00.device"
    )
    assert escape_name(".hidden") == "\\x2ehidden"


def test_serial_devices_come_from_the_processes_connection():
    argvs = [
        ["python", "-m", "dronewrapper_bridge_mavlink", "--set", "connection=/dev/ttyTHS1"],
        ["python", "-m", "x", "--set", "connection=udpin:127.0.0.1:14540"],
        ["python", "-m", "y", "--set", "source=/dev/video0"],
    ]
    assert serial_devices(argvs) == ["/dev/ttyTHS1"]


def spec(**changes) -> UnitSpec:
    base = dict(
        graph=Path("/home/j/dw/compose/px4_real_follow_person_secure.yaml"),
        user="jetson",
        command=["/home/j/dw/.venv/bin/python", "-m", "dronewrapper", "up", "/g.yaml",
                 "--var=serial=/dev/ttyTHS1", "--identity=drone1"],
        working_dir=Path("/home/j/dw"),
        devices=["/dev/ttyTHS1"],
        environment={"DRONEWRAPPER_ASSETS": "/home/j/assets"},
    )  # fmt: skip
    return UnitSpec(**{**base, **changes})


def sections(text: str) -> dict[str, list[str]]:
    out: dict[str, list[str]] = {}
    current = ""
    for line in text.splitlines():
        if line.startswith("["):
            current = line.strip("[]")
            out[current] = []
        elif line:
            out[current].append(line)
    return out


def test_the_unit_orders_restarts_logs_and_runs_as_the_user():
    unit = sections(render_unit(spec()))
    assert "Wants=network-online.target" in unit["Unit"]
    assert "After=network-online.target dev-ttyTHS1.device" in unit["Unit"]
    assert "Requires=dev-ttyTHS1.device" in unit["Unit"]
    service = unit["Service"]
    for line in ("User=jetson", "Restart=on-failure", "KillSignal=SIGINT",
                 "StandardOutput=journal", "WorkingDirectory=/home/j/dw",
                 "SupplementaryGroups=dialout video",
                 "Environment=DRONEWRAPPER_ASSETS=/home/j/assets",
                 "SyslogIdentifier=dronewrapper-px4_real_follow_person_secure"):  # fmt: skip
        assert line in service, line
    exec_start = next(line for line in service if line.startswith("ExecStart="))
    assert exec_start.endswith("--var=serial=/dev/ttyTHS1 --identity=drone1")
    assert unit["Install"] == ["WantedBy=multi-user.target"]


def test_a_graph_without_a_serial_device_waits_for_the_network_only():
    unit = sections(render_unit(spec(devices=[])))
    assert "After=network-online.target" in unit["Unit"]
    assert not any(line.startswith("Requires=") for line in unit["Unit"])


def test_dollars_and_percents_reach_the_command_as_they_are():
    text = render_unit(spec(command=["/bin/echo", "50%", "$HOME"]))
    assert "ExecStart=/bin/echo 50%% '$$HOME'" in text


def test_the_jetson_check_covers_every_third_party_requirement():
    requirements = third_party_requirements()
    names = {parse_requirement(r)[0] for r in requirements}
    for needed in ("eclipse-zenoh", "pymavlink", "pyserial", "onnxruntime", "cryptography",
                   "opencv-python-headless", "numpy", "msgspec"):  # fmt: skip
        assert needed in names, needed
    assert not any(name.startswith("dronewrapper") for name in names)
    assert "pytest" not in names  # the dev extra is not on board
    assert "manylinux2014_aarch64" in PLATFORMS and "manylinux_2_35_aarch64" in PLATFORMS
    assert missing_wheel("ERROR: No matching distribution found for lap>=0.4") == "lap>=0.4"
    assert parse_requirement("dronewrapper[images, security]>=1") == (
        "dronewrapper",
        ["images", "security"],
    )


def test_the_jetson_check_resolves_binary_wheels_for_aarch64_without_installing():
    argv = pip_resolve_argv(["lap>=0.4"], Path("/t"), Path("/r.json"))
    assert argv[argv.index("install") :][:2] == ["install", "--dry-run"]
    assert "--only-binary=:all:" in argv and argv[argv.index("--python-version") + 1] == "3.10"
    assert argv[argv.index("--report") + 1] == "/r.json" and argv[-1] == "lap>=0.4"
    report = {
        "install": [{"download_info": {"url": "https://x/lap-0.5-cp310-manylinux2014_aarch64.whl"}}]
    }
    assert wheel_names(report) == ["lap-0.5-cp310-manylinux2014_aarch64.whl"]
