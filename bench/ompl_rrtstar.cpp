// Compiled OMPL RRT* on one box-world query, for bench/planning.py.
//
// Usage: ompl_rrtstar PROBLEM_FILE SEED TIME_LIMIT_S
//
// PROBLEM_FILE holds whitespace-separated numbers, all in metres:
//   lower(3) upper(3)  start(3) goal(3)  range goal_bias rewire_factor  N  N x block(6)
// where the boundary and the blocks are already inflated by the safety margin and a block
// is (x_min, y_min, z_min, x_max, y_max, z_max). A state is valid when it is inside the
// boundary and in no closed block; a motion is valid when the closed segment meets no
// block (an exact slab test, no sampling along the segment).
//
// Solves twice in one process, the first time untimed (a warm-up), and prints one line
// of the second: "setup_s first_s length_m vertices" -- the set-up (space, checkers,
// problem, planner->setup) outside the clock, then the wall time of solve() stopped at the
// first exact solution, its length and the tree's size; first_s and length_m are "inf"
// when none was found in time.

#include <ompl/base/MotionValidator.h>
#include <ompl/base/PlannerTerminationCondition.h>
#include <ompl/base/ProblemDefinition.h>
#include <ompl/base/SpaceInformation.h>
#include <ompl/base/objectives/PathLengthOptimizationObjective.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/geometric/PathGeometric.h>
#include <ompl/geometric/planners/rrt/RRTstar.h>
#include <ompl/util/Console.h>
#include <ompl/util/RandomNumbers.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace ob = ompl::base;
namespace og = ompl::geometric;

using Box = std::array<double, 6>;

static const double *coords(const ob::State *s) {
    return s->as<ob::RealVectorStateSpace::StateType>()->values;
}

// Whether the closed segment p -> q meets the closed box b (slab test).
static bool segment_hits(const double *p, const double *q, const Box &b) {
    double t0 = 0.0, t1 = 1.0;
    for (int k = 0; k < 3; ++k) {
        const double d = q[k] - p[k];
        if (d == 0.0) {
            if (p[k] < b[k] || p[k] > b[k + 3]) return false;
            continue;
        }
        double ta = (b[k] - p[k]) / d, tb = (b[k + 3] - p[k]) / d;
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
        if (t0 > t1) return false;
    }
    return true;
}

class BoxValidity : public ob::StateValidityChecker {
public:
    BoxValidity(const ob::SpaceInformationPtr &si, const std::vector<Box> &blocks)
        : ob::StateValidityChecker(si), blocks_(blocks) {}
    bool isValid(const ob::State *state) const override {
        if (!si_->satisfiesBounds(state)) return false;
        const double *p = coords(state);
        for (const Box &b : blocks_)
            if (p[0] >= b[0] && p[0] <= b[3] && p[1] >= b[1] && p[1] <= b[4] &&
                p[2] >= b[2] && p[2] <= b[5])
                return false;
        return true;
    }

private:
    const std::vector<Box> &blocks_;
};

class BoxMotion : public ob::MotionValidator {
public:
    BoxMotion(const ob::SpaceInformationPtr &si, const std::vector<Box> &blocks)
        : ob::MotionValidator(si), blocks_(blocks) {}
    bool checkMotion(const ob::State *s1, const ob::State *s2) const override {
        if (!si_->isValid(s2)) return false;
        const double *p = coords(s1), *q = coords(s2);
        for (const Box &b : blocks_)
            if (segment_hits(p, q, b)) return false;
        return true;
    }
    bool checkMotion(const ob::State *s1, const ob::State *s2,
                     std::pair<ob::State *, double> &last_valid) const override {
        const bool ok = checkMotion(s1, s2);
        if (!ok) {  // RRT* never asks for the last valid state; report the start
            if (last_valid.first != nullptr) si_->copyState(last_valid.first, s1);
            last_valid.second = 0.0;
        }
        return ok;
    }

private:
    const std::vector<Box> &blocks_;
};

struct Query {
    double lower[3], upper[3], start[3], goal[3], range, goal_bias, rewire;
    std::vector<Box> blocks;
};

struct Run {
    double setup_s, first_s, length_m;
    unsigned vertices;
};

// Set up OMPL for the query (timed apart), then solve until the first solution.
static Run solve_once(const Query &q, double limit) {
    using clock = std::chrono::steady_clock;
    const auto setup_began = clock::now();
    auto space = std::make_shared<ob::RealVectorStateSpace>(3);
    ob::RealVectorBounds bounds(3);
    for (int k = 0; k < 3; ++k) {
        bounds.setLow(k, q.lower[k]);
        bounds.setHigh(k, q.upper[k]);
    }
    space->setBounds(bounds);
    auto si = std::make_shared<ob::SpaceInformation>(space);
    si->setStateValidityChecker(std::make_shared<BoxValidity>(si, q.blocks));
    si->setMotionValidator(std::make_shared<BoxMotion>(si, q.blocks));
    si->setup();
    ob::ScopedState<> s(space), g(space);
    for (int k = 0; k < 3; ++k) {
        s[k] = q.start[k];
        g[k] = q.goal[k];
    }
    auto pdef = std::make_shared<ob::ProblemDefinition>(si);
    pdef->setStartAndGoalStates(s, g, 1e-9);
    // Any solution meets this threshold, so RRT* stops at its first one (it adds its
    // solution to the problem only when solve() ends, so an exact-solution condition
    // would not stop it).
    auto objective = std::make_shared<ob::PathLengthOptimizationObjective>(si);
    objective->setCostThreshold(ob::Cost(std::numeric_limits<double>::infinity()));
    pdef->setOptimizationObjective(objective);
    auto planner = std::make_shared<og::RRTstar>(si);
    planner->setRange(q.range);
    planner->setGoalBias(q.goal_bias);
    planner->setRewireFactor(q.rewire);
    planner->setProblemDefinition(pdef);
    planner->setup();
    const double setup_s = std::chrono::duration<double>(clock::now() - setup_began).count();

    const auto began = clock::now();
    const ob::PlannerStatus status = planner->solve(ob::timedPlannerTerminationCondition(limit));
    const double first_s = std::chrono::duration<double>(clock::now() - began).count();
    ob::PlannerData data(si);
    planner->getPlannerData(data);
    const double inf = std::numeric_limits<double>::infinity();
    if (status != ob::PlannerStatus::EXACT_SOLUTION) return {setup_s, inf, inf, data.numVertices()};
    const double length = pdef->getSolutionPath()->as<og::PathGeometric>()->length();
    return {setup_s, first_s, length, data.numVertices()};
}

int main(int argc, char **argv) {
    if (argc != 4) {
        std::fprintf(stderr, "usage: %s PROBLEM_FILE SEED TIME_LIMIT_S\n", argv[0]);
        return 2;
    }
    std::ifstream in(argv[1]);
    Query q;
    std::size_t count = 0;
    for (double &v : q.lower) in >> v;
    for (double &v : q.upper) in >> v;
    for (double &v : q.start) in >> v;
    for (double &v : q.goal) in >> v;
    in >> q.range >> q.goal_bias >> q.rewire >> count;
    q.blocks.resize(count);
    for (Box &b : q.blocks)
        for (double &v : b) in >> v;
    if (!in) {
        std::fprintf(stderr, "%s: could not read the problem\n", argv[1]);
        return 2;
    }
    ompl::msg::setLogLevel(ompl::msg::LOG_NONE);
    ompl::RNG::setSeed(static_cast<std::uint_fast32_t>(std::stoul(argv[2])));
    const double limit = std::stod(argv[3]);
    // A first, untimed solve warms the process (lazy allocations, page faults, caches),
    // as our planner is warm after its kernels load; the second is the one reported.
    solve_once(q, limit);
    const Run run = solve_once(q, limit);
    std::printf("%.9g %.9g %.9g %u\n", run.setup_s, run.first_s, run.length_m, run.vertices);
    return 0;
}
