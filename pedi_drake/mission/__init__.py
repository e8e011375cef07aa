"""pedi_drake.mission."""
