"""The operator: commands from a person or a program (LCM, the Go1 remote) for the operation modes."""
