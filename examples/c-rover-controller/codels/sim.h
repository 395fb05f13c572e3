/* The rover's hardware as its codels see it: in this example a simulated world
 * (src/world.rs), where a real rover links its drivers. */
#ifndef ROVER_SIM_H
#define ROVER_SIM_H

/* Drives the wheels at linear speed v (m/s) and angular speed w (rad/s). */
void rover_sim_wheels(double v, double w);
/* The speeds the wheels turned at during the last filter period (0.1 s). */
void rover_sim_encoders(double *v, double *w);
/* Whether the straight line to (x, y) is blocked by an obstacle. */
int rover_sim_blocked(double x, double y);
/* The distance from the rover to (x, y), as its range sensor measures it. */
double rover_sim_distance(double x, double y);

#endif
