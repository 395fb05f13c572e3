/* The codels of robots/genom3/loco.gen: the wheels track a speed reference. */
#include "acloco.h"
#include "loco_c_types.h"

#include "hook.h"
#include "sim.h"

/* how much of the gap to the reference the wheels close per period */
#define LOCO_RAMP 0.5

genom_event
loco_motion_start(loco_ids *ids, const genom_context self)
{
  (void)self;
  ids->current.v = 0;
  ids->current.w = 0;
  ids->powered = true;
  return ROVER_OUTCOME(loco_ether, loco_ether);
}

genom_event
loco_init(bool *powered, const genom_context self)
{
  (void)self;
  *powered = true;
  return genom_ok;
}

genom_event
loco_move_start(const rover_speed *ref, rover_speed *current, const genom_context self)
{
  (void)ref;
  (void)self;
  current->v = 0;
  current->w = 0;
  return ROVER_OUTCOME(loco_pause_track, loco_pause_track);
}

genom_event
loco_move_track(const rover_speed *ref, rover_speed *current, bool powered,
                const genom_context self)
{
  genom_event own = loco_pause_track;
  if (!powered) {
    loco_e_motor_detail d = { .code = 1, .what = "motors off" };
    own = loco_e_motor(&d, self);
  } else {
    current->v += LOCO_RAMP * (ref->v - current->v);
    current->w += LOCO_RAMP * (ref->w - current->w);
    rover_sim_wheels(current->v, current->w);
  }
  return ROVER_OUTCOME(own, loco_pause_track, loco_ether, loco_e_motor_id);
}

genom_event
loco_move_stop(rover_speed *current, const genom_context self)
{
  (void)self;
  current->v = 0;
  current->w = 0;
  rover_sim_wheels(0, 0);
  return ROVER_OUTCOME(loco_ether, loco_ether, loco_e_motor_id);
}

genom_event
loco_stop(rover_speed *current, const genom_context self)
{
  (void)self;
  current->v = 0;
  current->w = 0;
  rover_sim_wheels(0, 0);
  return ROVER_OUTCOME(loco_ether, loco_ether);
}
