"""The engines' compiled (numba) kernels: a block's rounds, the policy's step and waypoint
draws, the targets' tracks, sensor-disc entry times, the lawnmower's legs and the swarms'
iterations. Arrays in, arrays out; nothing here imports the engines above it."""
