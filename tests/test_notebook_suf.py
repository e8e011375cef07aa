"""The prong design notebook executes headless and shows its figures."""


def test_suf_prong_design_notebook_executes(execute_notebook):
    outputs = execute_notebook("suf_prong_design.ipynb", timeout=120)
    assert not [o for o in outputs if o.output_type == "error"]
    text = "".join(o.get("text", "") for o in outputs)
    assert "SUF with prongs" in text and "best design with prongs" in text
    images = [o for o in outputs if o.output_type == "display_data" and "image/png" in o.get("data", {})]
    assert len(images) == 2  # the polytopes, SUF vs height
