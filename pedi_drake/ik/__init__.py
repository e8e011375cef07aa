"""pedi_drake.ik."""
