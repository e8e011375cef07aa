"""The mission analysis notebook runs a mission and plots its logs, headless."""


def test_mission_analysis_notebook_runs_the_mission_and_plots_its_logs(execute_notebook):
    outputs = execute_notebook("mission_analysis.ipynb", timeout=300)
    assert not [o for o in outputs if o.output_type == "error"]
    text = "".join(o.get("text", "") for o in outputs)
    assert "hit_target_front: succeeded" in text
    assert "final foot error" in text
    images = [o for o in outputs if o.output_type == "display_data" and "image/png" in o.get("data", {})]
    assert len(images) == 2  # errors over the phases, joint torques
