"""pedi_drake.viz."""
