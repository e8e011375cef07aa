"""The static walk: its cycles (gait), where the feet land (footholds) and its slot-by-slot plan
(static_walk). The walking mission phases that run it are in pedi_drake.mission.walk."""
