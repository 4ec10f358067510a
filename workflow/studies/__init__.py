"""Studies over many virtual-lab campaigns, shared by tests and benchmarks."""
