"""pedi_drake.station."""
