"""The echo command's pure helpers: key-expression hints, nearby keys, the silence notice, and
Zenoh errors shown as one line."""

from dronewrapper.echo import (
    ARRIVALS_KEPT,
    RateWatch,
    declared_rate,
    keyexpr_problem,
    light_key_families,
    nearby,
    silence_notice,
)
from dronewrapper.health import OK
from dronewrapper.runtime.errors import zenoh_error_text


def test_leading_slash_gets_a_hint_naming_the_right_key():
    assert "try 'drone/mavros/state'" in keyexpr_problem("/drone/mavros/state")


def test_empty_chunks_are_named():
    assert "empty chunk" in keyexpr_problem("drone//state")
    assert "empty chunk" in keyexpr_problem("drone/")
    assert keyexpr_problem("drone/**") is None


def test_light_families_leave_images_out():
    families = light_key_families()
    assert "*/mavros/state" in families
    assert not any("image_raw" in family for family in families)


def test_nearby_keys_are_ranked_by_likeness():
    seen = {"drone/mavros/state", "drone/mavros/battery", "sim/objects/target/pose"}
    assert nearby("drone/mavros/sate", seen)[0] == "drone/mavros/state"


def test_silence_notice_says_what_is_published_instead():
    text = silence_notice("drone1/mavros/state", 3.0, {"drone/mavros/state"})
    assert "nothing received on 'drone1/mavros/state' in 3 s" in text
    assert "published nearby: drone/mavros/state" in text
    assert "is the graph running" in silence_notice("drone/mavros/state", 3.0, set())


def test_zenoh_errors_lose_their_rust_source_paths():
    raw = (
        "Can not create a new TCP listener bound to tcp/1.2.3.4:9: [1.2.3.4:9: Cannot assign "
        "requested address (os error 99) at /root/.cargo/git/checkouts/zenoh-9c599/cc83980/io/"
        "zenoh-link-commons/src/tcp.rs:61.] at /root/.cargo/git/checkouts/zenoh-9c/cc83980/io/"
        "zenoh-links/zenoh-link-tcp/src/unicast.rs:338."
    )
    text = zenoh_error_text(ValueError(raw))
    assert ".rs" not in text and "/root/" not in text
    assert text.endswith("Cannot assign requested address (os error 99)]")
    assert "\n" not in zenoh_error_text(ValueError("a\nb  at /x/y.rs:1."))


def test_echo_watches_each_key_against_its_declared_rate():
    """Rates and ages against the registry, and one notice when a key goes stale."""
    watch = RateWatch()
    pose, text = "drone/mavros/local_position/pose", "drone/mavros/statustext/recv"
    for i in range(200):
        watch.add(pose, 100.0 + i / 30, 120)
    watch.add(text, 100.0, 40)
    last = 100.0 + 199 / 30
    assert len(watch.logs[pose].arrivals) <= 2 * ARRIVALS_KEPT  # bounded
    report = watch.report(last + 0.05)
    assert report[0].startswith(f"{pose}: 30.0 Hz (declared 30 Hz), newest 0.05 s old")
    assert report[1].startswith(f"{text}: - (event-driven)")
    assert watch.newly_stale(last + 0.4) == []
    stale = watch.newly_stale(last + 0.6)
    assert stale == [f"{pose} is stale: nothing for 0.6 s (declared 30 Hz, stale after 0.5 s)"]
    assert watch.newly_stale(last + 5.0) == []  # said once
    watch.add(pose, last + 5.0, 120)
    assert watch.newly_stale(last + 5.1) == []  # fresh again
    assert "stale" in watch.newly_stale(last + 6.0)[0]  # and stale again, said again


def test_echo_count_2_on_a_30_hz_camera_raises_no_rate_alarm():
    """Two frames (one a little late) measure no rate: no 'expected >= 30 Hz' alarm."""
    watch = RateWatch()
    camera = "drone/cam_frontal/image_raw"
    assert declared_rate(camera) == 30.0
    watch.add(camera, 10.0, 900_000)
    watch.add(camera, 10.0 + 0.07, 900_000)  # one frame late: 14 Hz from a single gap
    (health,) = watch.health(10.08)
    assert health.verdict == OK, health
    line = watch.report(10.08)[0]
    assert "expected >=" not in line and "too few to judge the rate" in line
    watch.add("drone/cam_ventral/image_raw", 10.01, 900_000)  # a key seen once
    assert all(h.verdict == OK for h in watch.health(10.08))
    for i in range(2, 8):  # enough frames at 10 Hz: now the alarm is real
        watch.add(camera, 10.0 + i * 0.1, 900_000)
    assert "expected >= 30 Hz" in watch.report(10.75)[0]
