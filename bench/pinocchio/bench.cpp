// Pinocchio peer benchmark for twinloop.
//
// Usage: bench_pinocchio MODEL_FILE STATES.csv [--rounds N] [--max-seconds S] [--check]
//
// MODEL_FILE is a URDF (.urdf) or MJCF (.xml) file. A free-flyer root joint is added unless the
// file already has a floating root (URDF `floating` joint below the root link, MJCF freejoint).
// URDF mimic joints are independent joints. Armature, rotor inertia, damping and friction are
// zeroed so that the algorithms work on the rigid-body model (as twinloop does).
//
// STATES.csv is the twinloop trajectory format (see README.md). Columns are mapped to Pinocchio's
// q/v indices by joint name; the floating root is always called "base".
//
// Every algorithm is timed over all states (the loop over states is inside the timed region),
// repeated for up to N rounds (default 200) or until S seconds (default 0.3) have been spent on
// that algorithm, whichever comes first (at least 5 rounds). The median over rounds of the time
// per call is printed as JSON on stdout.
//
// --check prints, instead of timing, the results of rnea, aba and com for the first state (JSON),
// to verify the CSV mapping against the Python bindings.

#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/center-of-mass.hpp>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/jacobian.hpp>
#include <pinocchio/algorithm/joint-configuration.hpp>
#include <pinocchio/algorithm/kinematics.hpp>
#include <pinocchio/algorithm/regressor.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/multibody.hpp>
#include <pinocchio/parsers/mjcf.hpp>
#include <pinocchio/parsers/urdf.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#ifndef BENCH_COMPILER_FLAGS
#define BENCH_COMPILER_FLAGS "unknown"
#endif

namespace {

using Model = pinocchio::Model;
using Data = pinocchio::Data;
using Vec = Eigen::VectorXd;

template <class T>
inline void escape(T const &value) {
  asm volatile("" : : "g"(&value) : "memory");
}

volatile double g_sink = 0.0;

[[noreturn]] void die(const std::string &msg) {
  std::cerr << "bench_pinocchio: " << msg << "\n";
  std::exit(2);
}

bool ends_with(const std::string &s, const std::string &suffix) {
  if (s.size() < suffix.size()) return false;
  std::string tail = s.substr(s.size() - suffix.size());
  std::transform(tail.begin(), tail.end(), tail.begin(), ::tolower);
  return tail == suffix;
}

std::string file_stem(const std::string &path) {
  std::string base = path.substr(path.find_last_of('/') + 1);
  auto dot = base.find_last_of('.');
  return dot == std::string::npos ? base : base.substr(0, dot);
}

bool is_free_flyer_root(const Model &m) {
  return m.njoints > 1 && m.parents[1] == 0 && m.joints[1].shortname() == "JointModelFreeFlyer";
}

// Returns the model and whether the floating root came from the file.
Model load_model(const std::string &path, bool &file_floating_root) {
  Model model;
  if (ends_with(path, ".urdf")) {
    pinocchio::urdf::buildModel(path, model, false, /*mimic=*/false);
    if (is_free_flyer_root(model)) {
      file_floating_root = true;
    } else {
      model = Model();
      pinocchio::urdf::buildModel(path, pinocchio::JointModelFreeFlyer(), model, false,
                                  /*mimic=*/false);
      file_floating_root = false;
    }
  } else if (ends_with(path, ".xml")) {
    pinocchio::mjcf::buildModel(path, model, false);
    if (is_free_flyer_root(model)) {
      file_floating_root = true;
    } else {
      model = Model();
      pinocchio::mjcf::buildModel(path, pinocchio::JointModelFreeFlyer(), model, false);
      file_floating_root = false;
    }
  } else {
    die("model file must end in .urdf or .xml: " + path);
  }
  if (!is_free_flyer_root(model)) die("no floating root joint after loading " + path);
  model.armature.setZero();
  model.rotorInertia.setZero();
  model.damping.setZero();
  model.friction.setZero();
  model.gravity.linear(Eigen::Vector3d(0.0, 0.0, -9.81));
  model.gravity.angular().setZero();
  return model;
}

struct State {
  Vec q, v, a, tau;
};

std::vector<std::string> split_csv_line(const std::string &line) {
  std::vector<std::string> out;
  std::string cur;
  bool quoted = false;
  for (char c : line) {
    if (c == '"') {
      quoted = !quoted;
    } else if (c == ',' && !quoted) {
      out.push_back(cur);
      cur.clear();
    } else if (c != '\r' && c != '\n') {
      cur.push_back(c);
    }
  }
  out.push_back(cur);
  for (auto &s : out) {
    auto b = s.find_first_not_of(" \t");
    auto e = s.find_last_not_of(" \t");
    s = b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
  }
  return out;
}

// Where one CSV column goes.
struct Target {
  enum Kind { Q, QAngle, V, A, Tau } kind;
  int index;  // idx_q (Q, QAngle) or idx_v
};

std::vector<State> read_states(const std::string &path, const Model &model) {
  std::ifstream in(path);
  if (!in) die("cannot open states file " + path);
  std::string line;
  if (!std::getline(in, line)) die("empty states file " + path);
  const std::vector<std::string> header = split_csv_line(line);
  std::map<std::string, int> col;
  for (size_t i = 0; i < header.size(); ++i) {
    if (col.count(header[i])) die("duplicate column " + header[i]);
    col[header[i]] = static_cast<int>(i);
  }

  // Build the column -> vector entry map from the model.
  std::vector<std::pair<int, Target>> map;
  std::vector<std::string> missing;
  auto need = [&](const std::string &name, Target t) {
    auto it = col.find(name);
    if (it == col.end()) {
      missing.push_back(name);
    } else {
      map.emplace_back(it->second, t);
    }
  };
  static const char *base_q[7] = {"x", "y", "z", "qx", "qy", "qz", "qw"};
  static const char *base_v[6] = {"vx", "vy", "vz", "wx", "wy", "wz"};
  static const char *base_f[6] = {"fx", "fy", "fz", "tx", "ty", "tz"};
  for (pinocchio::JointIndex j = 1; j < static_cast<pinocchio::JointIndex>(model.njoints); ++j) {
    const auto &jm = model.joints[j];
    const int iq = jm.idx_q(), iv = jm.idx_v();
    if (j == 1) {
      for (int k = 0; k < 7; ++k) need(std::string("q:base.") + base_q[k], {Target::Q, iq + k});
      for (int k = 0; k < 6; ++k) {
        need(std::string("v:base.") + base_v[k], {Target::V, iv + k});
        need(std::string("a:base.") + base_v[k], {Target::A, iv + k});
        need(std::string("tau:base.") + base_f[k], {Target::Tau, iv + k});
      }
      continue;
    }
    const std::string &name = model.names[j];
    if (jm.nq() == 1 && jm.nv() == 1) {
      need("q:" + name, {Target::Q, iq});
    } else if (jm.nq() == 2 && jm.nv() == 1) {  // continuous joint: angle -> (cos, sin)
      need("q:" + name, {Target::QAngle, iq});
    } else {
      die("joint " + name + " of type " + jm.shortname() + " is not supported");
    }
    need("v:" + name, {Target::V, iv});
    need("a:" + name, {Target::A, iv});
    need("tau:" + name, {Target::Tau, iv});
  }
  if (!missing.empty()) {
    std::string msg = "states file " + path + " lacks " + std::to_string(missing.size()) +
                      " column(s) needed by the model:";
    for (size_t i = 0; i < missing.size() && i < 20; ++i) msg += " " + missing[i];
    if (missing.size() > 20) msg += " ...";
    die(msg);
  }
  {
    std::vector<bool> used(header.size(), false);
    for (auto &m : map) used[m.first] = true;
    for (size_t i = 0; i < header.size(); ++i)
      if (!used[i] && header[i] != "t")
        std::cerr << "bench_pinocchio: warning: ignoring column " << header[i] << "\n";
  }

  std::vector<State> states;
  size_t lineno = 1;
  while (std::getline(in, line)) {
    ++lineno;
    if (line.find_first_not_of(" \t\r\n") == std::string::npos) continue;
    const auto fields = split_csv_line(line);
    if (fields.size() != header.size())
      die("line " + std::to_string(lineno) + ": " + std::to_string(fields.size()) +
          " fields, header has " + std::to_string(header.size()));
    State s{pinocchio::neutral(model), Vec::Zero(model.nv), Vec::Zero(model.nv),
            Vec::Zero(model.nv)};
    for (auto &m : map) {
      const std::string &f = fields[m.first];
      char *end = nullptr;
      const double x = std::strtod(f.c_str(), &end);
      if (f.empty() || *end != '\0')
        die("line " + std::to_string(lineno) + ": bad number '" + f + "' in column " +
            header[m.first]);
      switch (m.second.kind) {
        case Target::Q: s.q[m.second.index] = x; break;
        case Target::QAngle:
          s.q[m.second.index] = std::cos(x);
          s.q[m.second.index + 1] = std::sin(x);
          break;
        case Target::V: s.v[m.second.index] = x; break;
        case Target::A: s.a[m.second.index] = x; break;
        case Target::Tau: s.tau[m.second.index] = x; break;
      }
    }
    // Normalise the base quaternion (the CSV holds rounded values at best).
    const int iq = model.joints[1].idx_q();
    s.q.segment<4>(iq + 3).normalize();
    states.push_back(std::move(s));
  }
  if (states.empty()) die("no states in " + path);
  return states;
}

struct Timing {
  double median_ns;
  int rounds;
};

template <class F>
Timing time_algorithm(F &&call, size_t n_states, int max_rounds, double max_seconds) {
  using clock = std::chrono::steady_clock;
  for (size_t i = 0; i < n_states; ++i) call(i);  // warm-up round
  std::vector<double> per_call;
  per_call.reserve(max_rounds);
  const auto start = clock::now();
  for (int r = 0; r < max_rounds; ++r) {
    const auto t0 = clock::now();
    for (size_t i = 0; i < n_states; ++i) call(i);
    const auto t1 = clock::now();
    per_call.push_back(std::chrono::duration<double, std::nano>(t1 - t0).count() /
                       static_cast<double>(n_states));
    const double spent = std::chrono::duration<double>(t1 - start).count();
    if (max_seconds > 0 && spent >= max_seconds && per_call.size() >= 5) break;
  }
  std::sort(per_call.begin(), per_call.end());
  const size_t n = per_call.size();
  const double med = n % 2 ? per_call[n / 2] : 0.5 * (per_call[n / 2 - 1] + per_call[n / 2]);
  return {med, static_cast<int>(n)};
}

std::string json_vec(const Eigen::VectorXd &x) {
  std::ostringstream os;
  os.precision(17);
  os << "[";
  for (Eigen::Index i = 0; i < x.size(); ++i) os << (i ? "," : "") << x[i];
  os << "]";
  return os.str();
}

}  // namespace

int main(int argc, char **argv) {
  std::string model_path, states_path;
  int rounds = 200;
  double max_seconds = 0.3;
  bool check = false;
  for (int i = 1; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg == "--rounds" && i + 1 < argc) {
      rounds = std::atoi(argv[++i]);
      if (rounds < 1) die("--rounds must be >= 1");
    } else if (arg == "--max-seconds" && i + 1 < argc) {
      max_seconds = std::atof(argv[++i]);
    } else if (arg == "--check") {
      check = true;
    } else if (arg == "-h" || arg == "--help") {
      std::cout << "usage: bench_pinocchio MODEL_FILE STATES.csv [--rounds N] [--max-seconds S] "
                   "[--check]\n";
      return 0;
    } else if (!arg.empty() && arg[0] == '-') {
      die("unknown option " + arg);
    } else if (model_path.empty()) {
      model_path = arg;
    } else if (states_path.empty()) {
      states_path = arg;
    } else {
      die("too many arguments");
    }
  }
  if (model_path.empty() || states_path.empty())
    die("usage: bench_pinocchio MODEL_FILE STATES.csv [--rounds N] [--max-seconds S] [--check]");

  bool file_floating_root = false;
  Model model;
  try {
    model = load_model(model_path, file_floating_root);
  } catch (const std::exception &e) {
    die("cannot load " + model_path + ": " + e.what());
  }
  const std::vector<State> states = read_states(states_path, model);
  Data data(model);
  const size_t n = states.size();

  if (check) {
    const State &s = states[0];
    const Vec tau = pinocchio::rnea(model, data, s.q, s.v, s.a);
    const Vec ddq = pinocchio::aba(model, data, s.q, s.v, s.tau);
    const Eigen::Vector3d com = pinocchio::centerOfMass(model, data, s.q);
    std::cout << "{\"model\":\"" << file_stem(model_path) << "\",\"nv\":" << model.nv
              << ",\"q\":" << json_vec(s.q) << ",\"rnea\":" << json_vec(tau)
              << ",\"aba\":" << json_vec(ddq) << ",\"com\":" << json_vec(com) << "}\n";
    return 0;
  }

  struct Entry {
    const char *name;
    Timing t;
  };
  std::vector<Entry> results;

  results.push_back({"fk", time_algorithm(
                               [&](size_t i) {
                                 pinocchio::forwardKinematics(model, data, states[i].q);
                                 escape(data);
                               },
                               n, rounds, max_seconds)});
  g_sink = g_sink + data.oMi.back().translation()[0];
  results.push_back({"com", time_algorithm(
                                [&](size_t i) {
                                  pinocchio::centerOfMass(model, data, states[i].q);
                                  escape(data);
                                },
                                n, rounds, max_seconds)});
  g_sink = g_sink + data.com[0][0];
  results.push_back({"rnea", time_algorithm(
                                 [&](size_t i) {
                                   pinocchio::rnea(model, data, states[i].q, states[i].v,
                                                   states[i].a);
                                   escape(data);
                                 },
                                 n, rounds, max_seconds)});
  g_sink = g_sink + data.tau[0];
  // Pinocchio has two conventions for CRBA and ABA (LOCAL is the default, WORLD is
  // often faster): time both and let "crba"/"aba" be the faster, so twinloop is
  // compared with Pinocchio at its best.
  const Timing crba_local = time_algorithm(
    [&](size_t i) {
      pinocchio::crba(model, data, states[i].q, pinocchio::Convention::LOCAL);
      escape(data);
    },
    n, rounds, max_seconds);
  const Timing crba_world = time_algorithm(
    [&](size_t i) {
      pinocchio::crba(model, data, states[i].q, pinocchio::Convention::WORLD);
      escape(data);
    },
    n, rounds, max_seconds);
  g_sink = g_sink + data.M(0, 0);
  results.push_back({"crba", crba_local.median_ns <= crba_world.median_ns ? crba_local : crba_world});
  results.push_back({"crba_local", crba_local});
  results.push_back({"crba_world", crba_world});
  const Timing aba_local = time_algorithm(
    [&](size_t i) {
      pinocchio::aba(model, data, states[i].q, states[i].v, states[i].tau,
                     pinocchio::Convention::LOCAL);
      escape(data);
    },
    n, rounds, max_seconds);
  const Timing aba_world = time_algorithm(
    [&](size_t i) {
      pinocchio::aba(model, data, states[i].q, states[i].v, states[i].tau,
                     pinocchio::Convention::WORLD);
      escape(data);
    },
    n, rounds, max_seconds);
  g_sink = g_sink + data.ddq[0];
  results.push_back({"aba", aba_local.median_ns <= aba_world.median_ns ? aba_local : aba_world});
  results.push_back({"aba_local", aba_local});
  results.push_back({"aba_world", aba_world});
  results.push_back({"jacobians", time_algorithm(
                                      [&](size_t i) {
                                        pinocchio::computeJointJacobians(model, data, states[i].q);
                                        escape(data);
                                      },
                                      n, rounds, max_seconds)});
  g_sink = g_sink + data.J(0, 0);
  results.push_back({"regressor", time_algorithm(
                                      [&](size_t i) {
                                        pinocchio::computeJointTorqueRegressor(
                                          model, data, states[i].q, states[i].v, states[i].a);
                                        escape(data);
                                      },
                                      n, rounds, max_seconds)});
  g_sink = g_sink + data.jointTorqueRegressor(0, 0);

  std::ostringstream os;
  os.precision(6);
  os << "{\"model\": \"" << file_stem(model_path) << "\", \"nv\": " << model.nv
     << ", \"nq\": " << model.nq << ", \"njoints\": " << (model.njoints - 1)
     << ", \"states\": " << n << ", \"floating_base\": \""
     << (file_floating_root ? "file" : "added_freeflyer") << "\", \"ns_per_call\": {";
  for (size_t k = 0; k < results.size(); ++k)
    os << (k ? ", " : "") << "\"" << results[k].name << "\": " << results[k].t.median_ns;
  os << "}, \"rounds\": {";
  for (size_t k = 0; k < results.size(); ++k)
    os << (k ? ", " : "") << "\"" << results[k].name << "\": " << results[k].t.rounds;
  os << "}, \"pinocchio_version\": \"" << PINOCCHIO_VERSION << "\", \"compiler_flags\": \""
     << BENCH_COMPILER_FLAGS << "\"}";
  std::cout << os.str() << std::endl;
  return 0;
}
