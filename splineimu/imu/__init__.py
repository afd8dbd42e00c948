"""IMU synthesis: ideal measurements from motion, and the shared sensor model."""
