"""Measuring helpers for the benchmarks and the real-time runs: the CPU time the hypervisor took,
and which system's Python callbacks took a loop's time."""
