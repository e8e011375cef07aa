"""pedi_drake.dynamics: the Go1's rigid-body dynamics as the controllers and the live SUF see it,
computed in one compiled call from the state estimate and the measured joints."""
