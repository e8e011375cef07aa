"""pedi_drake.estimation."""
