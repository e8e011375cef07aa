"""pedi_drake.control."""
