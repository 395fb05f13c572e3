/* The test hook of hook.h. */
#include <stdint.h>

#include "genom3/c/exception.h"
#include "hook.h"

int rover_hook_mode = 0;
uint32_t rover_hook_seed = 1;
uint64_t rover_hook_undeclared = 0;

static const char nowhere[] = "::rover::nowhere";

genom_event
rover_hook(genom_event own, const genom_event *declared, int n)
{
  uint32_t r;
  if (rover_hook_mode == 0 || n <= 0) return own;
  rover_hook_seed = rover_hook_seed * 1103515245u + 12345u;
  r = rover_hook_seed >> 8;
  if (rover_hook_mode == 2 && r % 5 == 0) {
    rover_hook_undeclared++;
    return (r / 5) % 2 ? genom_ok : nowhere;
  }
  return declared[r % (uint32_t)n];
}
