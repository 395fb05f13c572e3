/* The codels of odo.gen: the wheels' encoders, published on port speed. */
#include "acodo.h"
#include "odo_c_types.h"

#include "hook.h"
#include "sim.h"

static genom_event
odo_publish(const odo_speed *speed, const genom_context self)
{
  rover_speed *out = speed->data(self);
  if (!out) return genom_fatal;
  rover_sim_encoders(&out->v, &out->w);
  return speed->write(self);
}

genom_event
odo_start(const odo_speed *speed, const genom_context self)
{
  if (odo_publish(speed, self) != genom_ok) return genom_fatal;
  return ROVER_OUTCOME(odo_pause_read, odo_pause_read);
}

genom_event
odo_read(const odo_speed *speed, const genom_context self)
{
  if (odo_publish(speed, self) != genom_ok) return genom_fatal;
  return ROVER_OUTCOME(odo_pause_read, odo_pause_read);
}
