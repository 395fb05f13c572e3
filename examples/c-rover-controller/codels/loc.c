/* The codels of robots/genom3/loc.gen: dead reckoning from the odometry odo publishes,
 * published on port pose. */
#include <math.h>

#include "acloc.h"
#include "loc_c_types.h"

#include "hook.h"

/* the filter's period, in seconds */
#define LOC_DT 0.1

genom_event
loc_track_start(uint32_t *n, const genom_context self)
{
  (void)self;
  *n = 0;
  return ROVER_OUTCOME(loc_pause_estimate, loc_pause_estimate);
}

genom_event
loc_track_estimate(const loc_odometry *odometry, uint32_t *n, rover_pose *estimate,
                   const loc_pose *pose, const genom_context self)
{
  double v = 0, w = 0;
  const rover_speed *measured;
  rover_pose *out;
  /* the speeds odo published (none yet: standing still) */
  if (odometry->read(self) != genom_ok) return genom_fatal;
  measured = odometry->data(self);
  if (measured) {
    v = measured->v;
    w = measured->w;
  }
  estimate->theta += w * LOC_DT;
  estimate->x += v * LOC_DT * cos(estimate->theta);
  estimate->y += v * LOC_DT * sin(estimate->theta);
  estimate->cov[0] += 0.01 * fabs(v) * LOC_DT;
  estimate->cov[4] = estimate->cov[0];
  (*n)++;
  out = pose->data(self);
  if (!out) return genom_fatal;
  *out = *estimate;
  if (pose->write(self) != genom_ok) return genom_fatal;
  return ROVER_OUTCOME(loc_pause_estimate, loc_pause_estimate, loc_ether);
}
