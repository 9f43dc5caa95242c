"""The page itself in a real headless Chromium, against an in-process station with the
stand-in bridge (see station_env): read-only observers, the token, the gamepad's dead-man
button, refusals shown with their reason. The simulated flight is tests/integration/
test_station_browser.py."""

from __future__ import annotations

import pytest
from selenium.webdriver.common.action_chains import ActionChains
from selenium.webdriver.common.by import By
from station_env import POSE, TOKEN, StationEnv, station_env

from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import MASK_POSITION, CommandBool
from dronewrapper_ground_station.browser import chromium, console_errors
from support import REPO, client_node, wait_for

pytestmark = pytest.mark.timeout(120)

OTHER_NAME = "station.test"  # resolves to 127.0.0.1 in this browser only: not a loopback name

# a stand-in for the Gamepad API (headless Chromium has no gamepads): the page reads
# navigator.getGamepads() as with a real pad; the test moves its sticks and buttons
FAKE_GAMEPAD = """
window.fakePad = {connected: true, axes: [0, 0, 0, 0],
                  buttons: Array.from({length: 16}, () => ({pressed: false, value: 0}))};
navigator.getGamepads = () => [window.fakePad];
"""


@pytest.fixture
def env(router):
    with station_env(router, simulator=True) as env:  # its world shown, not a 503 logged
        yield env


@pytest.fixture(scope="module")
def browser(tmp_path_factory: pytest.TempPathFactory):
    """One Chromium for the module (starting one takes seconds); each test's station listens
    on a new port, so no page state (storage, cookies) is shared between tests."""
    rules = f"--host-resolver-rules=MAP {OTHER_NAME} 127.0.0.1"
    with chromium(tmp_path_factory.mktemp("chromium") / "profile", extra_flags=[rules]) as driver:
        yield driver


@pytest.fixture
def driver(browser):
    console_errors(browser)  # drop what an earlier test's page logged
    yield browser
    browser.get("about:blank")  # the page stops polling its station before that one closes


def _open(driver, env: StationEnv, host: str = "127.0.0.1", query: str = "") -> None:
    driver.get(f"http://{host}:{env.port}/{query}")
    wait_for(
        lambda: driver.execute_script("return window.station.ns && window.station.drone"),
        20,
        what="the page to show the drone",
    )


def test_a_real_aircraft_without_simulator_is_said_without_an_error(router, driver) -> None:
    """No simulator answers the world query (a real aircraft): the page says so and the
    browser logs no failed request."""
    with station_env(router) as env:
        _open(driver, env)
        hidden = "return document.getElementById('scenario-select').hidden"
        wait_for(lambda: driver.execute_script(hidden), 20, what="the world query answered")
        assert driver.find_element(By.ID, "world-state").text == "no simulator"
        assert console_errors(driver) == []
        driver.get("about:blank")


def test_observer_page_is_read_only(env: StationEnv, driver, router) -> None:
    probe = client_node(router, name="probe")
    setpoints = probe.latest(registry.SETPOINT_RAW_LOCAL)
    _open(driver, env, OTHER_NAME)
    assert driver.execute_script("return window.station.role") == "observer"
    assert driver.find_element(By.ID, "readonly").is_displayed()
    for button in ("btn-arm", "btn-takeoff", "btn-land", "btn-mode"):
        assert not driver.find_element(By.ID, button).is_enabled(), button
    stick = driver.find_element(By.ID, "stick-right")
    ActionChains(driver, duration=50).move_to_element(stick).click_and_hold().move_by_offset(
        0, -60
    ).pause(1.0).release().perform()
    driver.find_element(By.TAG_NAME, "body").send_keys("wwww")
    probe.close()
    assert setpoints.count == 0, "an observer's page commanded the drone"
    assert driver.find_element(By.ID, "tm-position").text.startswith("position")
    assert console_errors(driver) == []


def test_the_token_makes_an_operator_and_leaves_the_address_bar(env: StationEnv, driver) -> None:
    _open(driver, env, OTHER_NAME, f"?token={TOKEN}")
    assert driver.execute_script("return window.station.role") == "operator"
    assert TOKEN not in driver.current_url
    driver.find_element(By.ID, "btn-arm").click()
    wait_for(lambda: "arm: done" in driver.find_element(By.ID, "result").text, 10, what="arm")
    assert env.bridge.requests[-1] == CommandBool(value=True)
    assert console_errors(driver) == []


def test_refusals_show_the_reason(env: StationEnv, driver) -> None:
    _open(driver, env)
    driver.find_element(By.ID, "btn-disarm").click()
    result = driver.find_element(By.ID, "result")
    wait_for(lambda: "disarming denied in flight" in result.text, 10, what="the reason")
    assert "bad" in result.get_attribute("class")


def test_gamepad_drives_only_while_its_dead_man_is_held(env: StationEnv, driver, router) -> None:
    _open(driver, env)
    driver.execute_script(FAKE_GAMEPAD)
    link = env.fleet.get("drone")
    with client_node(router, name="probe") as probe:
        setpoints = probe.latest(registry.SETPOINT_RAW_LOCAL)
        driver.execute_script("window.fakePad.axes[3] = -1")  # right stick fully forward
        wait_for(
            lambda: "hold LB" in driver.find_element(By.ID, "gamepad").text, 5, what="pad seen"
        )
        assert not link.deadman.active  # sticks without the dead-man button do nothing
        driver.execute_script("window.fakePad.buttons[4].pressed = true")
        sp = wait_for(
            lambda: (s := setpoints.fresh(0.5)) and s.type_mask != MASK_POSITION and s,
            5,
            what="velocity setpoints",
        )
        assert sp.velocity.x == env.config.teleop.horizontal
        assert link.deadman.active
        driver.execute_script("window.fakePad.buttons[4].pressed = false")
        sp = wait_for(
            lambda: (s := setpoints.fresh(0.5)) and s.type_mask == MASK_POSITION and s,
            5,
            what="a hold on release",
        )
        assert (sp.position.x, sp.position.y, sp.position.z) == POSE
    assert console_errors(driver) == []


LAYOUT_SHOT = REPO / "out" / "station_1280.png"


def test_at_1280_px_the_log_sits_by_the_buttons_and_plots_are_sharp(env: StationEnv, driver):
    """On a 1280 px wide window the log (where refusal reasons go) is right below the command
    buttons, on the first screen, and each plot's canvas has one pixel per device pixel (not
    a small bitmap stretched), with labels in the page's small font. Screenshots are saved to
    ``out/station_1280.png`` and ``out/station_1280_plots.png``."""
    size = driver.get_window_size()
    driver.set_window_size(1280, 800)
    try:
        _open(driver, env)
        driver.find_element(By.ID, "btn-disarm").click()  # a refusal, logged with its reason
        wait_for(lambda: driver.find_elements(By.CSS_SELECTOR, "#log li"), 10, what="a log line")
        box = driver.execute_script(
            "const r = (id) => document.getElementById(id).getBoundingClientRect();"
            "const buttons = document.getElementById('btn-arm').closest('.panel');"
            "return {buttons: buttons.getBoundingClientRect(), log: r('log'),"
            " viewport: window.innerHeight};"
        )
        gap = box["log"]["top"] - box["buttons"]["bottom"]
        assert 0 <= gap <= 80, f"the log starts {gap:.0f} px below the buttons"
        assert box["log"]["top"] < box["viewport"], "the log is off the first screen"
        plots = driver.execute_script(
            "const dpr = window.devicePixelRatio || 1;"
            "return [...document.querySelectorAll('canvas.plot')].map((c) => ({"
            "  id: c.id, width: c.width, height: c.height, dpr: dpr,"
            "  cssWidth: c.clientWidth, cssHeight: c.clientHeight,"
            "  font: c.getContext('2d').font}));"
        )
        assert len(plots) == 3
        for plot in plots:
            assert plot["width"] == round(plot["cssWidth"] * plot["dpr"]), plot
            assert plot["height"] == round(plot["cssHeight"] * plot["dpr"]), plot
            assert plot["font"].startswith("12px"), plot  # the .muted text's size, in CSS px
        LAYOUT_SHOT.parent.mkdir(exist_ok=True)
        driver.save_screenshot(str(LAYOUT_SHOT))
        driver.execute_script("document.getElementById('plot-alt').scrollIntoView()")
        driver.save_screenshot(str(LAYOUT_SHOT.with_name("station_1280_plots.png")))
    finally:
        driver.set_window_size(size["width"], size["height"])
