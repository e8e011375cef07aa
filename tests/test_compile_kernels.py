"""compile_kernels: which diagrams it builds, in which order its workers take them, its options."""

import pytest

from pedi_drake.apps.compile_kernels import CONTROLLERS, compile_kernels, main, schedule, uses_prongs, variants


def test_the_workers_start_on_each_controller_tick_and_the_shared_kernels_apart():
    built = variants()
    order = schedule(built)
    assert sorted((job.mission, job.controller, job.hardware) for job in order if not job.controller_only) == sorted(
        built
    )
    leading = order[: 2 * len(CONTROLLERS)]
    keys = [(job.controller, uses_prongs(job.mission), job.controller_only) for job in leading]
    # The plain Go1's whole-body tick alone beside a whole diagram of paper 002's controller (the
    # kernels every diagram shares, then its tick), then the ticks with prongs alone.
    assert keys == [
        ("whole_body", False, True),
        ("projected_impedance", False, False),
        ("whole_body", True, True),
        ("projected_impedance", True, True),
    ]
    assert not any(job.hardware for job in leading)


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
