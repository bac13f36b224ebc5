#pragma once
// The cross-check: the rigid envs (cartpole1, cartpole3, bounce, pinball-1x2, pinball-4x4) run
// for seeded parameter vectors in our simulators, MuJoCo 2.2 and Bullet 3, and every pair of
// engines is compared on what the models share (reference/README.md explains each quantity and
// tolerance):
//   - cartpoles (no contact): the tip position over the whole horizon and the final loss;
//   - contact setups: the ball's free flight before the first impact (the same semi-implicit
//     recursion in every engine), the step of the first impact, the first impact's rebound, the
//     number of ground bounces and the final position (the contact models differ: penalty vs
//     soft constraint vs impulses, so some of these are reported without a tolerance).
// `harness crosscheck [--env NAME]` prints the table through run_crosscheck().
// The parts: events.hpp (contact events of a rollout), setup.hpp (each env's setup in every
// engine, its seeded vectors and tolerances), this file (the rows and the table).
#include <ostream>
#include <string>
#include <vector>

#include "reference/events.hpp"
#include "reference/setup.hpp"

namespace dsb {

// true when this build has MuJoCo or Bullet (the rows of a missing engine are left out)
bool crosscheck_available();

// Prints the table for `envs` (empty = all five rigid envs) to `out`; returns 0 when every
// tolerance holds, 1 when one fails or no engine is built. Throws UsageError naming an env the
// cross-check does not know.
int run_crosscheck(const std::vector<std::string>& envs, std::ostream& out);

namespace reference {

// one row of the table: the worst case over the env's parameter vectors
struct CrosscheckRow {
  std::string env, engines;
  int vectors = 0;
  double deviation = 0.0, free_flight = 0.0, loss = 0.0, final_position = 0.0, rebound = 0.0;
  int first_impact = 0, bounces = 0;
  bool contact = false;  // a contact setup (free flight, impact and bounce columns apply)
  Tolerances tol;
  bool pass = true;
  std::string failure;  // which quantity failed first, with the parameter vector's index
};

// the rows of the table for `envs` (empty = all), each pair of the available engines
std::vector<CrosscheckRow> crosscheck(const std::vector<std::string>& envs);
void print_crosscheck(const std::vector<CrosscheckRow>& rows, std::ostream& out);

}  // namespace reference
}  // namespace dsb
