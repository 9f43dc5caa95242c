"""Every shell and Python snippet of README.md and docs/ is run by the docs test or excluded
with a reason (tests/doc_snippets.py): a new snippet must be placed, a stale entry removed."""

from __future__ import annotations

import re

from doc_snippets import DOCS, DRONE_ADDRESSES, PLAN, REPO, Excluded, Run, code_lines, snippets


def test_every_snippet_is_run_or_excluded_with_a_reason():
    found = {s.key for s in snippets()}
    assert len(found) == len(snippets()), "two snippets of one page start alike"
    assert found - PLAN.keys() == set(), "snippets nobody runs or excludes (add to PLAN)"
    assert PLAN.keys() - found == set(), "PLAN entries for snippets that moved or went"
    for where, plan in PLAN.items():
        assert isinstance(plan, Run | Excluded), where
        if isinstance(plan, Excluded):
            assert len(plan.reason) > 20, where
        else:
            assert all(len(why) > 10 for why in plan.skip.values()), where


def test_a_snippet_run_as_another_is_the_same_code():
    by_key = {s.key: s for s in snippets()}
    for where, plan in PLAN.items():
        if isinstance(plan, Run) and plan.same_as:
            assert code_lines(by_key[where].text) == code_lines(by_key[plan.same_as].text)


def test_most_snippets_run():
    runs = [w for w, p in PLAN.items() if isinstance(p, Run)]
    assert len(runs) >= 15, runs


def test_a_documented_sdk_install_has_the_extras_its_snippets_use():
    """A laptop install line must be enough for the snippets of the same page."""
    for doc in DOCS:
        text = (REPO / doc).read_text(encoding="utf-8")
        for extras in re.findall(r"pip install '\./sdk\[([a-z,]+)\]'", text):
            given = set(extras.split(","))
            if "compressed_images=True" in text:
                assert "images" in given, f"{doc}: compressed_images=True needs the images extra"
            if 'identity="' in text:
                assert "security" in given, f"{doc}: an identity needs the security extra"


def test_the_docs_name_one_address_for_the_drone():
    for doc in DOCS:
        text = (REPO / doc).read_text(encoding="utf-8")
        for address in re.findall(r"tls/192\.168\.\d+\.\d+:\d+", text):
            assert address in DRONE_ADDRESSES, (
                f"{doc}: {address}, the README says {DRONE_ADDRESSES}"
            )
