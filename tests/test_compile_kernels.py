"""compile_kernels: which diagrams it builds, in which order its workers take them, its options."""

import pytest

from pedi_drake.apps.compile_kernels import CONTROLLERS, compile_kernels, main, schedule, uses_prongs, variants


def test_the_workers_start_on_one_variant_of_each_controller_and_contact_count():
    built = variants()
    order = schedule(built)
    assert sorted(order) == sorted(built)
    leading = order[: 2 * len(CONTROLLERS)]
    keys = [(controller, uses_prongs(mission)) for mission, controller, hardware in leading]
    assert not any(hardware for _, _, hardware in leading)
    # The whole-body ticks (the largest compiles) first, one without prongs and one with.
    assert keys == [(controller, prongs) for controller in CONTROLLERS for prongs in (False, True)]


def test_prong_missions_are_told_apart_from_the_plain_go1():
    assert uses_prongs("prong_push_box")
    assert not uses_prongs("hit_target_front")


def test_no_worker_is_refused():
    with pytest.raises(ValueError, match="jobs"):
        compile_kernels(jobs=0)


@pytest.mark.parametrize(
    "argv, message",
    [(["--jobs", "0"], "--jobs"), (["--profile", "--jobs", "2"], "--jobs 1"), (["--jobs", "two"], "--jobs")],
)
def test_bad_options_exit_2_naming_the_option(argv, message, capsys):
    with pytest.raises(SystemExit) as stop:
        main(argv)
    assert stop.value.code == 2
    assert message in capsys.readouterr().err
