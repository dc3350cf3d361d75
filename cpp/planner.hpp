// drake_mh._native.MotionPlanner: rrt_connect's compiled planner and motion check
// (rrt_connect.hpp, motion.hpp) bound to one scene's packed buffers, for module.cpp. Its
// arguments mirror drake_mh/planning/rrt_connect/search.py plan_kernel and certify_motions; the
// Python side validates user input before the call (this checks shapes and ranges only, so
// that no call can read out of bounds).
#pragma once

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <cmath>
#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

#include "borrow.hpp"
#include "lazy_prm.hpp"

namespace dmh {

class MotionPlanner {
public:
    std::mutex busy;  // held by a call: the workspaces are the object's own

    MotionPlanner(Buffers buffers, std::vector<double> reach, int64_t nq)
        : buffers_(std::move(buffers)), reach_(std::move(reach)) {
        ok_ = unpack(buffers_.ints, buffers_.n_ints, buffers_.floats, buffers_.n_floats, s_);
        if (!ok_) return;
        for (int64_t k = 0; k < s_.K; ++k) ok_ = ok_ && s_.kinds[k] >= SPHERE && s_.kinds[k] <= CLOUD;
        int64_t need = 0;
        for (int64_t k = 0; k < s_.chain.F; ++k) need = std::max(need, s_.chain.qidx[k] + 1);
        const int64_t C = s_.G + s_.P;
        ok_ = ok_ && nq >= need && nq >= 1 && (int64_t)reach_.size() == C * nq;
        if (ok_) mc_ = std::make_unique<MotionChecker>(s_, reach_.data(), nq, C);
    }

    bool ok() const { return ok_; }
    int64_t nq() const { return mc_->nq; }

    // The motion checks' options; the workspaces are rebuilt only when they change, and a call
    // starts from a fresh memory of the last collision (as the kernels' fresh workspaces).
    void set_options(const MotionOptions& o, double* stats) {
        const MotionOptions& c = mc_->o;
        if (!configured_ || c.clearance != o.clearance || c.self_clearance != o.self_clearance ||
            c.lanes0 != o.lanes0 || c.lanes1 != o.lanes1 || c.probes != o.probes || c.interior != o.interior)
            mc_->configure(o);
        else
            mc_->o = o, mc_->ws.forget(s_);
        configured_ = true;
        mc_->stats = stats;
    }

    PlanResult plan(const PlanOptions& po, const double* q_start, const double* goals, int64_t G, const double* lower,
                    const double* upper, uint64_t seed, int64_t max_nodes, double time_limit) {
        return rrt_connect(*mc_, po, q_start, goals, G, lower, upper, seed, max_nodes, time_limit);
    }

    // Informed lazy PRM* (lazy_prm.hpp prm_search), its samples checked by the boolean check of
    // the same buffers (built at the first call).
    int prm(const PrmOptions& po, const double* q_start, const double* goals, int64_t G, const double* init_path,
            int64_t M0, int64_t init_goal, const double* lower, const double* upper, uint64_t seed,
            int64_t max_samples, double time_limit, std::vector<double>& path, int64_t& goal) {
        if (!checker_) checker_ = std::make_unique<CollisionChecker>(buffers_);
        double* stats = mc_->stats;
        for (int64_t i = 0; i < PRM_N_STATS; ++i) stats[i] = 0.0;
        SplitMix64 rng{seed};
        const Deadline clock{now(), time_limit};
        return prm_search(*mc_, *checker_, rng, clock, q_start, goals, G, init_path, M0, init_goal, lower, upper,
                          max_samples, po, path, goal);
    }

    void certify(const double* QA, const double* QB, int64_t M, bool* out) {
        const int64_t nq = mc_->nq;
        for (int64_t i = 0; i < M; ++i) out[i] = mc_->certified_motion(QA + i * nq, QB + i * nq, false);
    }

private:
    Buffers buffers_;
    std::vector<double> reach_;
    Packed s_;
    bool ok_ = false, configured_ = false;
    std::unique_ptr<MotionChecker> mc_;
    std::unique_ptr<CollisionChecker> checker_;
};

}  // namespace dmh

namespace planner_binding {

namespace nb = nanobind;
using namespace nb::literals;
using CInts = nb::ndarray<const int64_t, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
using CVec = nb::ndarray<const double, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
using CMat = nb::ndarray<const double, nb::ndim<2>, nb::c_contig, nb::device::cpu>;
using Stats = nb::ndarray<double, nb::ndim<1>, nb::c_contig, nb::device::cpu>;

inline void check(bool ok, const char* what) {
    if (!ok) throw nb::value_error(what);
}

inline dmh::MotionOptions motion_options(double clearance, double self_clearance, double resolution, double margin,
                                         int64_t lanes0, int64_t lanes1, int64_t probes, int64_t interior,
                                         int64_t max_evals, bool profile) {
    check(std::isfinite(clearance) && clearance >= 0.0 && std::isfinite(self_clearance) && self_clearance >= 0.0,
          "clearances must be finite and >= 0");
    check(std::isfinite(resolution) && resolution > 0.0 && std::isfinite(margin) && margin > 0.0,
          "resolution and margin must be finite and > 0");
    check(lanes0 >= 1 && lanes1 >= 1 && lanes0 <= 4096 && lanes1 <= 4096, "lanes and block must be in [1, 4096]");
    check(probes >= 0 && probes <= 8 && interior >= 0 && interior <= 8, "probes must be in [0, 8]");
    check(max_evals >= 0, "max_certify_evaluations must be >= 0");
    dmh::MotionOptions o;
    o.clearance = clearance, o.self_clearance = self_clearance, o.resolution = resolution, o.margin = margin;
    o.lanes0 = lanes0, o.lanes1 = lanes1, o.probes = probes, o.interior = interior, o.max_evals = max_evals;
    o.profile = profile;
    return o;
}

inline void init(dmh::MotionPlanner* self, CInts ints, CVec floats, CMat reach) {
    new (self) dmh::MotionPlanner(dmh::borrow(ints, floats),
                                  std::vector<double>(reach.data(), reach.data() + reach.shape(0) * reach.shape(1)),
                                  (int64_t)reach.shape(1));
    if (!self->ok()) {
        self->~MotionPlanner();
        throw nb::value_error("MotionPlanner: the packed buffers and reach (G + P, nq) do not hold a collision model "
                              "(drake_mh.scene.kernels.packing.pack, CollisionModel.reach)");
    }
}

inline nb::tuple plan(dmh::MotionPlanner& self, CVec q_start, CMat goals, CVec lower, CVec upper, double clearance,
                      double self_clearance, uint64_t seed, int64_t max_nodes, double time_limit, CVec options,
                      Stats stats) {
    const size_t nq = (size_t)self.nq(), G = goals.shape(0);
    check(q_start.shape(0) == nq && goals.shape(1) == nq && G >= 1 && lower.shape(0) == nq && upper.shape(0) == nq,
          "plan: q_start (nq,), goals (G >= 1, nq), lower and upper (nq,)");
    check(options.shape(0) == 15 && stats.shape(0) == dmh::NSTATS, "plan: options (15,) and stats (NSTATS,)");
    check(max_nodes >= 0 && !std::isnan(time_limit), "plan: max_nodes >= 0 and a time limit that is a number");
    const double* op = options.data();
    for (size_t j = 0; j < nq; ++j)
        check(std::isfinite(q_start.data()[j]) && std::isfinite(lower.data()[j]) && std::isfinite(upper.data()[j]),
              "plan: q_start and the limits must be finite");
    for (size_t j = 0; j < G * nq; ++j) check(std::isfinite(goals.data()[j]), "plan: the goals must be finite");
    const dmh::MotionOptions mo = motion_options(clearance, self_clearance, op[1], op[2], (int64_t)op[3],
                                                 (int64_t)op[4], (int64_t)op[5], (int64_t)op[6], (int64_t)op[9],
                                                 op[13] != 0.0);
    dmh::PlanOptions po;
    po.step = op[0], po.goal_bias = op[7], po.balance = op[8] != 0.0, po.shortcut_iterations = (int64_t)op[10];
    po.shortcut_min_gain = op[11], po.domain_radius = op[14];
    check(std::isfinite(po.step) && po.step > 0.0 && std::isfinite(po.domain_radius) && po.domain_radius >= 0.0 &&
              po.goal_bias >= 0.0 && po.goal_bias <= 1.0 && po.shortcut_iterations >= 0,
          "plan: step > 0, domain_radius >= 0, goal_bias in [0, 1], shortcut_iterations >= 0");
    dmh::PlanResult result;
    {
        nb::gil_scoped_release unlocked;
        std::lock_guard<std::mutex> one_call(self.busy);
        self.set_options(mo, stats.data());
        result = self.plan(po, q_start.data(), goals.data(), (int64_t)G, lower.data(), upper.data(), seed, max_nodes,
                           time_limit);
    }
    const size_t M = (size_t)result.path.rows();
    double* path = new double[M * nq + 1];
    std::copy(result.path.q.begin(), result.path.q.end(), path);
    nb::capsule owner(path, [](void* p) noexcept { delete[] static_cast<double*>(p); });
    return nb::make_tuple(nb::ndarray<nb::numpy, double>(path, {M, nq}, owner), result.outcome, result.goal);
}

inline nb::tuple prm(dmh::MotionPlanner& self, CVec q_start, CMat goals, CMat init_path, int64_t init_goal, CVec lower,
                     CVec upper, double clearance, double self_clearance, uint64_t seed, int64_t max_samples,
                     double time_limit, CVec options, Stats stats) {
    const size_t nq = (size_t)self.nq(), G = goals.shape(0), M0 = init_path.shape(0);
    check(q_start.shape(0) == nq && goals.shape(1) == nq && G >= 1 && lower.shape(0) == nq && upper.shape(0) == nq &&
              (M0 == 0 || init_path.shape(1) == nq) && (M0 < 2 || (init_goal >= 0 && (size_t)init_goal < G)),
          "prm: q_start (nq,), goals (G >= 1, nq), init_path (M, nq) to goals[init_goal], lower and upper (nq,)");
    check(options.shape(0) == 12 && stats.shape(0) == dmh::PRM_N_STATS, "prm: options (12,) and stats (N_STATS,)");
    check(max_samples >= 0 && !std::isnan(time_limit), "prm: max_samples >= 0 and a time limit that is a number");
    for (size_t j = 0; j < nq; ++j)
        check(std::isfinite(q_start.data()[j]) && std::isfinite(lower.data()[j]) && std::isfinite(upper.data()[j]),
              "prm: q_start and the limits must be finite");
    for (size_t j = 0; j < G * nq; ++j) check(std::isfinite(goals.data()[j]), "prm: the goals must be finite");
    for (size_t j = 0; j < M0 * nq; ++j) check(std::isfinite(init_path.data()[j]), "prm: init_path must be finite");
    const double* op = options.data();  // lazy_prm_star/search.py OPTION_NAMES
    const dmh::MotionOptions mo = motion_options(clearance, self_clearance, op[2], op[3], (int64_t)op[4],
                                                 (int64_t)op[5], (int64_t)op[6], (int64_t)op[7], (int64_t)op[8], false);
    dmh::PrmOptions po;
    po.batch = (int64_t)op[0], po.k_scale = op[1], po.shortcut_iterations = (int64_t)op[9];
    po.shortcut_min_gain = op[10];
    check(po.batch >= 1 && std::isfinite(po.k_scale) && po.k_scale > 0.0 && po.shortcut_iterations >= 0,
          "prm: batch >= 1, k_scale > 0, shortcut_iterations >= 0");
    std::vector<double> best;
    int64_t goal = -1;
    int outcome;
    {
        nb::gil_scoped_release unlocked;
        std::lock_guard<std::mutex> one_call(self.busy);
        self.set_options(mo, stats.data());
        outcome = self.prm(po, q_start.data(), goals.data(), (int64_t)G, init_path.data(), (int64_t)M0, init_goal,
                           lower.data(), upper.data(), seed, max_samples, time_limit, best, goal);
    }
    const size_t M = best.size() / nq;
    double* path = new double[M * nq + 1];
    std::copy(best.begin(), best.end(), path);
    nb::capsule owner(path, [](void* p) noexcept { delete[] static_cast<double*>(p); });
    return nb::make_tuple(nb::ndarray<nb::numpy, double>(path, {M, nq}, owner), outcome, goal);
}

inline nb::object certify_motions(dmh::MotionPlanner& self, CMat QA, CMat QB, double clearance, double self_clearance,
                                  double resolution, double margin, int64_t lanes0, int64_t lanes1, int64_t probes,
                                  int64_t max_evals, Stats stats) {
    const size_t nq = (size_t)self.nq(), M = QA.shape(0);
    check(QA.shape(1) == nq && QB.shape(0) == M && QB.shape(1) == nq, "certify_motions: QA and QB (M, nq)");
    check(stats.shape(0) == dmh::NSTATS, "certify_motions: stats (NSTATS,)");
    for (size_t j = 0; j < M * nq; ++j)
        check(std::isfinite(QA.data()[j]) && std::isfinite(QB.data()[j]), "certify_motions: QA and QB must be finite");
    const dmh::MotionOptions mo =
        motion_options(clearance, self_clearance, resolution, margin, lanes0, lanes1, probes, 0, max_evals, false);
    bool* out = new bool[M + 1];
    nb::capsule owner(out, [](void* p) noexcept { delete[] static_cast<bool*>(p); });
    {
        nb::gil_scoped_release unlocked;
        std::lock_guard<std::mutex> one_call(self.busy);
        self.set_options(mo, stats.data());
        self.certify(QA.data(), QB.data(), (int64_t)M, out);
    }
    return nb::cast(nb::ndarray<nb::numpy, bool, nb::ndim<1>>(out, {M}, owner));
}

}  // namespace planner_binding

inline void bind_planner(nanobind::module_& m) {
    namespace nb = nanobind;
    using namespace nb::literals;
    m.attr("stat_count") = (int)dmh::NSTATS;
    nb::class_<dmh::MotionPlanner>(m, "MotionPlanner",
        "rrt_connect's planner and certified motion check (drake_mh/planning/rrt_connect/search.py plan_kernel and\n"
        "certify_motions, by_values None) on a scene's packed buffers (ints, floats) and the sphere model's reach\n"
        "(G + P, nq). Holds copies and its own workspaces: calls on one planner run one at a time, without the GIL.")
        .def("__init__", &planner_binding::init, "ints"_a, "floats"_a, "reach"_a)
        .def_prop_ro("nq", &dmh::MotionPlanner::nq)
        .def("plan", &planner_binding::plan, "q_start"_a, "goals"_a, "lower"_a, "upper"_a, "clearance"_a,
             "self_clearance"_a, "seed"_a, "max_nodes"_a, "time_limit"_a, "options"_a, "stats"_a,
             "(path (M, nq), outcome, goal) of plan_kernel's arguments (options: search.OPTION_NAMES; its clock entry\n"
             "is not read), stats (len(STAT_NAMES),) float64 set; path empty (0, nq) unless FOUND.")
        .def("prm", &planner_binding::prm, "q_start"_a, "goals"_a, "init_path"_a, "init_goal"_a, "lower"_a, "upper"_a,
             "clearance"_a, "self_clearance"_a, "seed"_a, "max_samples"_a, "time_limit"_a, "options"_a, "stats"_a,
             "(path (M, nq), outcome, goal) of lazy_prm_star/search.py prm_kernel's arguments (options: its\n"
             "OPTION_NAMES, the clock entry not read), stats (N_STATS,) float64 set; path empty unless FOUND.")
        .def("certify_motions", &planner_binding::certify_motions, "QA"_a, "QB"_a, "clearance"_a, "self_clearance"_a,
             "resolution"_a, "margin"_a, "first_lanes"_a, "block_lanes"_a, "probes"_a, "max_evals"_a, "stats"_a,
             "(M,) bool: search.certify_motions's answers for the motions QA[i] -> QB[i] (M, nq); stats added to.");
}
