/* The codels of robots/genom3/nav.gen: a straight route to the goal, followed until the
 * range sensor says the rover is within the tolerance. */
#include "acnav.h"
#include "nav_c_types.h"

#include "hook.h"
#include "sim.h"

genom_event
nav_goto_plan(const rover_pose *goal, rover_path *route, const genom_context self)
{
  genom_event own = nav_pause_move;
  /* a bounded sequence comes with its bound, as GenoM3 gives it */
  if (route->_maximum != 16) return genom_fatal;
  if (rover_sim_blocked(goal->x, goal->y)) {
    own = nav_e_blocked(self);
  } else {
    route->_length = 1;
    route->_buffer[0] = *goal;
  }
  return ROVER_OUTCOME(own, nav_pause_move, nav_e_blocked_id);
}

genom_event
nav_goto_move(const rover_path *route, double tolerance, rover_path *plan,
              const genom_context self)
{
  genom_event own = nav_pause_move;
  const rover_pose *goal;
  uint32_t k;
  (void)self;
  /* a bounded sequence's _maximum is const: its elements are copied */
  plan->_length = route->_length;
  for (k = 0; k < route->_length && k < plan->_maximum; k++)
    plan->_buffer[k] = route->_buffer[k];
  if (plan->_length == 0) {
    own = nav_ether;
  } else {
    goal = &plan->_buffer[plan->_length - 1];
    if (rover_sim_distance(goal->x, goal->y) <= tolerance) own = nav_ether;
  }
  return ROVER_OUTCOME(own, nav_pause_move, nav_ether, nav_e_blocked_id);
}

genom_event
nav_goto_stop(rover_path *plan, const genom_context self)
{
  (void)self;
  plan->_length = 0;
  return ROVER_OUTCOME(nav_ether, nav_ether, nav_e_blocked_id);
}
