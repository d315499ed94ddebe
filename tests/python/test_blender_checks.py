"""Every Blender check of tests/blender/registry.py as a test of its own, id "group/name" (the same
list tests/blender/run.py runs under bpy 5.2 and the Blender binaries). In this process under
bpy 4.2, the add-on enabled in place from addon/; the groups of registry.CHILD_GROUPS in a child
Python instead (tests/blender/run.py --only ...): the first test of such a group runs, in one
child, every check of that group this session selected, so its duration is the group's, and each
test reports its own check's outcome and output."""

import blender_checks
import harness  # before bpy
import pytest
import registry

CHECKS = tuple(registry.checks())
_child_outcomes: dict[str, tuple[str, str]] = {}


def _selected(session, group: str) -> list[str]:
    """The ids of this session's tests of `group` that can run here."""
    checks = (item.callspec.params["check"] for item in session.items if getattr(item, "obj", None) is test_check)
    return [c.id for c in checks if c.group == group and not c.skip_reason(binary=False)]


@pytest.mark.parametrize("check", CHECKS, ids=lambda check: check.id)
def test_check(check, request, tmp_path):
    reason = check.skip_reason(binary=False)
    if reason:
        pytest.skip(reason)
    if check.child:
        if check.id not in _child_outcomes:
            ids = _selected(request.session, check.group)
            zip_path = None
            if any(c.zip for c in CHECKS if c.id in ids):
                zip_path = blender_checks.ZIP
                assert zip_path.exists(), f"no {zip_path}: `make addon` builds it (make check a cp311-only one)"
            _child_outcomes.update(blender_checks.run_in_child(ids, zip_path=zip_path))
        outcome, output = _child_outcomes[check.id]
        assert outcome == "PASS", output
        print(output)  # the child's output for this check (pytest -s or -rP shows it)
    else:
        if check.group in registry.ADDON_GROUPS:
            harness.enable_addon_from_source()
        check.run(tmp_path)
