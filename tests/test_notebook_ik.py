"""The IK benchmark notebook executes headless."""

import time


def test_ik_benchmark_notebook_executes_within_60_s(execute_notebook):
    start = time.perf_counter()
    outputs = execute_notebook("ik_benchmark.ipynb", timeout=60)
    assert time.perf_counter() - start < 60.0
    assert not [o for o in outputs if o.output_type == "error"]
    assert any("Paper cube" in o.get("text", "") for o in outputs)
    images = [o for o in outputs if o.output_type == "display_data" and "image/png" in o.get("data", {})]
    assert len(images) == 2  # the 3D target plot and the error histogram
