"""Recognition judged on people it never saw (`python -m tools.evaluation.evaluate`)."""
