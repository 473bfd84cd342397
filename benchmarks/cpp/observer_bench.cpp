// C++ reference figures for one momentum-observer step (issue 22).
//
// Built and run by benchmarks/bench_cpp.py, which writes the inputs and
// compares the residuals with the Python MomentumObserver. By hand:
//
//   observer_bench ROBOT.urdf SAMPLES.csv OUT_DIR DT GAIN REPEAT
//
// ROBOT.urdf   the arm, every movable joint an observer joint (Pinocchio's
//              URDF parser; fixed joints are merged into their links).
// SAMPLES.csv  one header line, then one row per sample (time along the
//              rows): q [rad] (n_dof columns), qd [rad/s] (n_dof), tau [N m]
//              (n_dof).
// OUT_DIR      where residual_<variant>.csv are written, one row per sample,
//              n_dof columns [N m], 17 significant digits.
// DT, GAIN     sample period [s] and observer gain K_I [1/s] (every joint).
// REPEAT       timed passes over all samples per variant, the variants taking
//              turns; the median per sample is printed.
//
// Timed, per sample, on the same samples:
//   (a) crba + computeCoriolisMatrix + computeGeneralizedGravity (and each alone);
//   (b) (a) + the first-order momentum-observer update of sensorless'
//       MomentumObserver (torque held over the period, exact increment of p,
//       trapezoid rule for Cᵀq̇ − g, r_k = a r_k−1 + (1 − a) u_k,
//       a = exp(−K_I dt)), no friction;
//   (c) with -DWITH_EXT_OBSERVER and ext_observer's lib/ on the include path:
//       ext_observer's MomentumObserver (S. Mikhel, MIT licence) on the same
//       three Pinocchio calls; its own discretisation, so its residual is
//       close to, not equal to, (b)'s;
//   (d) a dedicated O(n) recursion for p = M q̇, Cᵀq̇ and g (no M, no C) +
//       the update of (b).
// Output on stdout, tab-separated: "time<TAB>label<TAB>µs per sample" and
// "check<TAB>label<TAB>value".

#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/multibody.hpp>
#include <pinocchio/parsers/urdf.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#ifdef WITH_EXT_OBSERVER
#include "momentum_observer.h"  // ext_observer/lib, from the build's include path
#endif

namespace bench {

using Eigen::MatrixXd;
using Eigen::VectorXd;
// The wheel's libpinocchio_default instantiates the algorithms for Ref<const VectorXd>
// arguments (PINOCCHIO_ENABLE_TEMPLATE_INSTANTIATION): passing Refs calls that compiled
// code, as the Python bindings do, instead of instantiating it here.
using In = Eigen::Ref<const VectorXd>;

struct Samples {
  std::vector<VectorXd> q, qd, tau;
};

Samples read_samples(const std::string& path, int n_dof) {
  std::ifstream file(path);
  if (!file) throw std::runtime_error("cannot open samples file " + path);
  Samples s;
  std::string line;
  std::getline(file, line);  // header
  while (std::getline(file, line)) {
    if (line.empty()) continue;
    std::vector<double> row;
    const char* c = line.c_str();
    char* end = nullptr;
    while (*c) {
      row.push_back(std::strtod(c, &end));
      if (end == c) throw std::runtime_error("bad number in " + path + ": " + line);
      c = end;
      if (*c == ',') ++c;
    }
    if (static_cast<int>(row.size()) != 3 * n_dof) {
      throw std::runtime_error("expected 3 x " + std::to_string(n_dof) + " columns in " + path +
                               "; got " + std::to_string(row.size()));
    }
    s.q.push_back(Eigen::Map<VectorXd>(row.data(), n_dof));
    s.qd.push_back(Eigen::Map<VectorXd>(row.data() + n_dof, n_dof));
    s.tau.push_back(Eigen::Map<VectorXd>(row.data() + 2 * n_dof, n_dof));
  }
  if (s.q.empty()) throw std::runtime_error("no samples in " + path);
  return s;
}

void write_rows(const std::string& path, const std::vector<VectorXd>& rows) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (!f) throw std::runtime_error("cannot write " + path);
  for (const VectorXd& r : rows) {
    for (Eigen::Index j = 0; j < r.size(); ++j) std::fprintf(f, j ? ",%.17g" : "%.17g", r[j]);
    std::fputc('\n', f);
  }
  std::fclose(f);
}

struct Variant {
  std::string label;
  std::function<void()> body;  // one pass over all samples
};

// Per variant, the median over `repeat` passes of the wall time per sample [µs]. The
// variants take turns (one pass each, `repeat` rounds, after one warm-up round), so that a
// load that changes during the run weighs on all of them alike.
std::vector<double> median_us(const std::vector<Variant>& variants, std::size_t n_samples,
                              int repeat) {
  std::vector<std::vector<double>> times(variants.size());
  for (const Variant& v : variants) v.body();
  for (int round = 0; round < repeat; ++round) {
    for (std::size_t i = 0; i < variants.size(); ++i) {
      const auto start = std::chrono::steady_clock::now();
      variants[i].body();
      const std::chrono::duration<double> elapsed = std::chrono::steady_clock::now() - start;
      times[i].push_back(elapsed.count() / static_cast<double>(n_samples) * 1e6);
    }
  }
  std::vector<double> medians;
  for (std::vector<double>& t : times) {
    std::sort(t.begin(), t.end());
    const std::size_t m = t.size() / 2;
    medians.push_back(t.size() % 2 ? t[m] : 0.5 * (t[m - 1] + t[m]));
  }
  return medians;
}

// The discrete update of sensorless.observers.MomentumObserver (no friction).
// Its state at the first sample is that of a robot moving with constant
// momentum under the balancing torque, so the first residual is 0.
class Update {
 public:
  Update(int n_dof, double dt, double gain)
      : dt_(dt), pole_(std::exp(-gain * dt)), weight_(-std::expm1(-gain * dt)),
        p_(n_dof), vg_(n_dof), tau_(n_dof), r_(n_dof) {}

  // p = M q̇ and vg = Cᵀq̇ − g at this sample, tau its torque; returns r̂ at this sample.
  const VectorXd& step(const VectorXd& p, const VectorXd& vg, const VectorXd& tau) {
    if (!started_) {
      p_ = p;
      vg_ = vg;
      tau_ = -vg;
      r_.setZero();
      started_ = true;
    }
    for (Eigen::Index j = 0; j < p.size(); ++j) {
      const double u = (p[j] - p_[j]) / dt_ - 0.5 * (vg_[j] + vg[j]) - tau_[j];
      r_[j] = weight_ * u + pole_ * r_[j];
    }
    p_ = p;
    vg_ = vg;
    tau_ = tau;
    return r_;
  }

  void reset() { started_ = false; }

 private:
  double dt_, pole_, weight_;
  VectorXd p_, vg_, tau_, r_;
  bool started_ = false;
};

// p = M q̇, Cᵀq̇ and g by one forward and one backward sweep, in joint frames.
// Joints: 1-dof revolute or prismatic about/along any axis.
class Recursion {
 public:
  explicit Recursion(const pinocchio::Model& model)
      : model_(model), n_(model.njoints - 1), axis_(n_), revolute_(n_), parent_(n_), idx_(n_),
        placement_(n_), frame_(n_), v_(model.njoints), ag_(model.njoints),
        h_(model.njoints), f_(model.njoints), s_(n_) {
    for (int i = 1; i <= n_; ++i) {
      const int k = i - 1;
      const auto& joint = model.joints[i];
      const std::string kind = joint.shortname();
      const auto& variant = joint.toVariant();
      if (kind == "JointModelRX" || kind == "JointModelRY" || kind == "JointModelRZ" ||
          kind == "JointModelPX" || kind == "JointModelPY" || kind == "JointModelPZ") {
        axis_[k] = Eigen::Vector3d::Unit(kind.back() - 'X');
        revolute_[k] = kind[10] == 'R';
      } else if (auto* r = boost::get<pinocchio::JointModelRevoluteUnaligned>(&variant)) {
        axis_[k] = r->axis;
        revolute_[k] = true;
      } else if (auto* t = boost::get<pinocchio::JointModelPrismaticUnaligned>(&variant)) {
        axis_[k] = t->axis;
        revolute_[k] = false;
      } else {
        throw std::runtime_error("the recursion handles revolute and prismatic joints only; "
                                 "joint " + model.names[i] + " is " + kind);
      }
      s_[k] = revolute_[k] ? pinocchio::Motion(Eigen::Vector3d::Zero(), axis_[k])
                           : pinocchio::Motion(axis_[k], Eigen::Vector3d::Zero());
      parent_[k] = static_cast<int>(model.parents[i]);
      idx_[k] = joint.idx_v();
      placement_[k] = model.jointPlacements[i];
    }
    v_[0].setZero();
    ag_[0] = -model.gravity;  // Pinocchio's convention: a_0 = −g, τ = Sᵀ Σ I a
  }

  void terms(const VectorXd& q, const VectorXd& qd, VectorXd& p, VectorXd& ct_qd, VectorXd& g) {
    for (int i = 1; i <= n_; ++i) {
      const int k = i - 1;
      const double x = q[idx_[k]];
      pinocchio::SE3 joint_motion = pinocchio::SE3::Identity();
      if (revolute_[k]) {
        joint_motion.rotation() = Eigen::AngleAxisd(x, axis_[k]).toRotationMatrix();
      } else {
        joint_motion.translation() = axis_[k] * x;
      }
      frame_[k] = placement_[k] * joint_motion;
      v_[i] = frame_[k].actInv(v_[parent_[k]]) + s_[k] * qd[idx_[k]];
      ag_[i] = frame_[k].actInv(ag_[parent_[k]]);
      h_[i] = model_.inertias[i] * v_[i];
      f_[i] = model_.inertias[i] * ag_[i];
    }
    for (int i = n_; i >= 1; --i) {
      const int k = i - 1;
      const int dof = idx_[k];
      p[dof] = s_[k].dot(h_[i]) + model_.armature[dof] * qd[dof];
      ct_qd[dof] = v_[i].cross(s_[k]).dot(h_[i]);
      g[dof] = s_[k].dot(f_[i]);
      if (parent_[k] > 0) {
        h_[parent_[k]] += frame_[k].act(h_[i]);
        f_[parent_[k]] += frame_[k].act(f_[i]);
      }
    }
  }

 private:
  const pinocchio::Model& model_;
  int n_;
  std::vector<Eigen::Vector3d> axis_;
  std::vector<bool> revolute_;
  std::vector<int> parent_, idx_;
  std::vector<pinocchio::SE3> placement_, frame_;
  std::vector<pinocchio::Motion> v_, ag_;
  std::vector<pinocchio::Force> h_, f_;
  std::vector<pinocchio::Motion> s_;
};

#ifdef WITH_EXT_OBSERVER
// ext_observer's robot interface, answered by the three standard Pinocchio calls.
class PinocchioDynamics final : public RobotDynamics {
 public:
  explicit PinocchioDynamics(const pinocchio::Model& model)
      : model_(model), data_(model), zero_(VectorXd::Zero(model.nv)) {}
  MatrixJ getM(VectorJ& q) override {
    pinocchio::crba(model_, data_, In(q));
    data_.M.triangularView<Eigen::StrictlyLower>() =
        data_.M.transpose().triangularView<Eigen::StrictlyLower>();
    return data_.M;
  }
  MatrixJ getC(VectorJ& q, VectorJ& qd) override {
    return pinocchio::computeCoriolisMatrix(model_, data_, In(q), In(qd));
  }
  VectorJ getG(VectorJ& q) override {
    return pinocchio::computeGeneralizedGravity(model_, data_, In(q));
  }
  VectorJ getFriction(VectorJ& /*qd*/) override { return zero_; }
  int jointNo() override { return static_cast<int>(model_.nv); }

 private:
  const pinocchio::Model& model_;
  pinocchio::Data data_;
  VectorXd zero_;
};
#endif

int run(int argc, char** argv) {
  if (argc != 7) {
    std::cerr << "usage: observer_bench ROBOT.urdf SAMPLES.csv OUT_DIR DT GAIN REPEAT\n";
    return 2;
  }
  const std::string urdf = argv[1], samples_path = argv[2], out_dir = argv[3];
  const double dt = std::atof(argv[4]), gain = std::atof(argv[5]);
  const int repeat = std::atoi(argv[6]);
  if (!(dt > 0) || !(gain > 0) || repeat < 1) {
    std::cerr << "DT and GAIN must be > 0 and REPEAT >= 1\n";
    return 2;
  }

  pinocchio::Model model;
  pinocchio::urdf::buildModel(urdf, model);
  pinocchio::Data data(model);
  const int n = static_cast<int>(model.nv);
  const Samples s = read_samples(samples_path, n);
  const std::size_t count = s.q.size();
  std::cout << "check\tn_dof\t" << n << "\ncheck\tsamples\t" << count << "\n";

  double sink = 0.0;  // keeps every timed result alive
  std::vector<Variant> variants;

  // (a) the three standard calls, together and alone
  variants.push_back({"(a) crba + computeCoriolisMatrix + computeGeneralizedGravity", [&] {
    for (std::size_t k = 0; k < count; ++k) {
      pinocchio::crba(model, data, In(s.q[k]));
      pinocchio::computeCoriolisMatrix(model, data, In(s.q[k]), In(s.qd[k]));
      pinocchio::computeGeneralizedGravity(model, data, In(s.q[k]));
      sink += data.M(0, 0) + data.C(0, 0) + data.g[0];
    }
  }});
  variants.push_back({"(a) crba alone", [&] {
    for (std::size_t k = 0; k < count; ++k) sink += pinocchio::crba(model, data, In(s.q[k]))(0, 0);
  }});
  variants.push_back({"(a) computeCoriolisMatrix alone", [&] {
    for (std::size_t k = 0; k < count; ++k)
      sink += pinocchio::computeCoriolisMatrix(model, data, In(s.q[k]), In(s.qd[k]))(0, 0);
  }});
  variants.push_back({"(a) computeGeneralizedGravity alone", [&] {
    for (std::size_t k = 0; k < count; ++k)
      sink += pinocchio::computeGeneralizedGravity(model, data, In(s.q[k]))[0];
  }});

  // (b) the calls + the observer update
  Update update(n, dt, gain);
  VectorXd p(n), vg(n), ct_qd(n), g(n);
  std::vector<VectorXd> residual_b(count), residual_c(count), residual_d(count);
  variants.push_back({"(b) standard calls + observer update", [&] {
    update.reset();
    for (std::size_t k = 0; k < count; ++k) {
      pinocchio::crba(model, data, In(s.q[k]));
      pinocchio::computeCoriolisMatrix(model, data, In(s.q[k]), In(s.qd[k]));
      pinocchio::computeGeneralizedGravity(model, data, In(s.q[k]));
      p.noalias() = data.M.selfadjointView<Eigen::Upper>() * s.qd[k];
      vg.noalias() = data.C.transpose() * s.qd[k];
      vg -= data.g;
      residual_b[k] = update.step(p, vg, s.tau[k]);
    }
  }});

#ifdef WITH_EXT_OBSERVER
  // (c) ext_observer's MomentumObserver on the standard calls
  PinocchioDynamics dynamics(model);
  VectorXd gains = VectorXd::Constant(n, gain);
  ::MomentumObserver ext_observer(&dynamics, gains);
  std::vector<VectorXd> q(s.q), qd(s.qd), tau(s.tau);  // its interface takes non-const refs
  variants.push_back({"(c) ext_observer MomentumObserver on the standard calls", [&] {
    ext_observer.reset();
    for (std::size_t k = 0; k < count; ++k)
      residual_c[k] = ext_observer.getExternalTorque(q[k], qd[k], tau[k], dt);
  }});
#endif

  // (d) the dedicated recursion, checked against the standard calls first
  Recursion recursion(model);
  double error = 0.0, scale = 0.0;
  for (std::size_t k = 0; k < count; k += std::max<std::size_t>(1, count / 500)) {
    recursion.terms(s.q[k], s.qd[k], p, ct_qd, g);
    pinocchio::crba(model, data, In(s.q[k]));
    pinocchio::computeCoriolisMatrix(model, data, In(s.q[k]), In(s.qd[k]));
    pinocchio::computeGeneralizedGravity(model, data, In(s.q[k]));
    const VectorXd p_ref = data.M.selfadjointView<Eigen::Upper>() * s.qd[k];
    const VectorXd c_ref = data.C.transpose() * s.qd[k];
    error = std::max({error, (p - p_ref).cwiseAbs().maxCoeff(),
                      (ct_qd - c_ref).cwiseAbs().maxCoeff(), (g - data.g).cwiseAbs().maxCoeff()});
    scale = std::max({scale, p_ref.cwiseAbs().maxCoeff(), c_ref.cwiseAbs().maxCoeff(),
                      data.g.cwiseAbs().maxCoeff()});
  }
  std::cout << "check\trecursion relative error\t" << error / scale << "\n";
  variants.push_back({"(d) O(n) recursion for p, Cᵀq̇, g alone", [&] {
    for (std::size_t k = 0; k < count; ++k) {
      recursion.terms(s.q[k], s.qd[k], p, ct_qd, g);
      sink += p[0] + ct_qd[0] + g[0];
    }
  }});
  variants.push_back({"(d) O(n) recursion + observer update", [&] {
    update.reset();
    for (std::size_t k = 0; k < count; ++k) {
      recursion.terms(s.q[k], s.qd[k], p, ct_qd, g);
      vg = ct_qd - g;
      residual_d[k] = update.step(p, vg, s.tau[k]);
    }
  }});

  const std::vector<double> medians = median_us(variants, count, repeat);
  for (std::size_t i = 0; i < variants.size(); ++i)
    std::cout << "time\t" << variants[i].label << "\t" << medians[i] << "\n";
  write_rows(out_dir + "/residual_standard.csv", residual_b);
#ifdef WITH_EXT_OBSERVER
  write_rows(out_dir + "/residual_ext_observer.csv", residual_c);
#endif
  write_rows(out_dir + "/residual_recursion.csv", residual_d);

  std::cout << "check\tsink\t" << sink << "\n";
  return 0;
}

}  // namespace bench

int main(int argc, char** argv) {
  try {
    return bench::run(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "observer_bench: " << e.what() << "\n";
    return 1;
  }
}
