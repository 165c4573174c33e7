"""The simulation process: it runs the world and the engines, carries out commands, samples each tick."""
