"""pedi_drake.numerics: maintained numerical libraries called from compiled kernels (DAQP's QP
solver, LAPACK's QR factorisations), for the controllers and the live SUF."""
