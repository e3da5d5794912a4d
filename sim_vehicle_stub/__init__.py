"""MAVLink vehicle emulator: many vehicles in one world, the paper's dynamics, targets and sensors."""
