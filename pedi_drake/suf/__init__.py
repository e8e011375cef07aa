"""pedi_drake.suf."""
