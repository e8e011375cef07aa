"""Runtime machinery: real-time scheduling, Ctrl-C and SIGTERM as stop requests, the host's wall
clock as a signal, a sample-and-hold in front of loggers, and the compiled kernels' cache."""
