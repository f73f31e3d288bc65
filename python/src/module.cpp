// SPDX-License-Identifier: BSD-3-Clause
// _slam2d: the C++ library for Python (pybind11, numpy). The Pythonic layer is slam2d/__init__.py.
// Arrays come in as float64 N x 2 (points) or N (ranges) and go out as numpy arrays; long calls
// release the GIL.

#include <fmt/core.h>
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <string>

#include "localize_job.hpp"
#include "map_job.hpp"
#include "slam2d/grid/occupancy_grid.hpp"
#include "slam2d/io/log_reader.hpp"
#include "slam2d/io/map_io.hpp"
#include "slam2d/localization/session.hpp"
#include "slam2d/methods/method_presets.hpp"
#include "slam2d/slam/graph/graph_slam.hpp"
#include "slam2d/slam/hector/hector_slam.hpp"
#include "slam2d/slam/rbpf/rbpf_slam.hpp"
#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/core/laser_scan.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/eval/relation_error.hpp"
#include "slam2d/io/config_file.hpp"
#include "slam2d/io/relations.hpp"
#include "slam2d/methods/matcher_registry.hpp"

namespace py = pybind11;

namespace slam2d {
namespace {

using Points = py::array_t<double, py::array::c_style | py::array::forcecast>;

/// N x 2 float64 points as a cloud (one copy: PointCloud2 owns Eigen points).
PointCloud2 cloud_from(const Points& points, const char* name) {
  if (points.ndim() != 2 || points.shape(1) != 2) {
    throw py::value_error(std::string(name) + " must be an N x 2 array of points");
  }
  PointCloud2 cloud;
  const auto view = points.unchecked<2>();
  cloud.points.resize(static_cast<std::size_t>(view.shape(0)));
  for (py::ssize_t i = 0; i < view.shape(0); ++i) cloud.points[static_cast<std::size_t>(i)] = {view(i, 0), view(i, 1)};
  return cloud;
}

/// A cloud's points as an N x 2 array.
py::array_t<double> points_array(const PointCloud2& cloud) {
  py::array_t<double> out({static_cast<py::ssize_t>(cloud.size()), py::ssize_t{2}});
  auto view = out.mutable_unchecked<2>();
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    view(static_cast<py::ssize_t>(i), 0) = cloud.points[i].x();
    view(static_cast<py::ssize_t>(i), 1) = cloud.points[i].y();
  }
  return out;
}

/// A trajectory as an N x 4 array: t, x, y, theta.
py::array_t<double> trajectory_array(const Trajectory& trajectory) {
  py::array_t<double> out({static_cast<py::ssize_t>(trajectory.size()), py::ssize_t{4}});
  auto view = out.mutable_unchecked<2>();
  for (std::size_t i = 0; i < trajectory.size(); ++i) {
    const auto row = static_cast<py::ssize_t>(i);
    view(row, 0) = trajectory[i].stamp;
    view(row, 1) = trajectory[i].pose.x();
    view(row, 2) = trajectory[i].pose.y();
    view(row, 3) = trajectory[i].pose.theta();
  }
  return out;
}

Trajectory trajectory_from(const Points& rows) {
  if (rows.ndim() != 2 || rows.shape(1) != 4) throw py::value_error("a trajectory is an N x 4 array: t, x, y, theta");
  const auto view = rows.unchecked<2>();
  Trajectory trajectory;
  trajectory.reserve(static_cast<std::size_t>(view.shape(0)));
  for (py::ssize_t i = 0; i < view.shape(0); ++i) trajectory.push_back(view(i, 0), SE2(view(i, 1), view(i, 2), view(i, 3)));
  return trajectory;
}

/// The map's cells as a height x width int8 array (row 0 at the smallest y; -1 unknown, 0..100).
py::dict map_dict(const OccupancyMap& map) {
  py::array_t<std::int8_t> cells({static_cast<py::ssize_t>(map.height), static_cast<py::ssize_t>(map.width)});
  std::copy(map.cells.begin(), map.cells.end(), cells.mutable_data());
  py::dict out;
  out["cells"] = cells;
  out["resolution"] = map.resolution;
  out["origin"] = map.origin;
  return out;
}

/// A scan's ranges as a float64 array (a copy: the scan owns them).
py::array_t<double> ranges_array(const LaserScan& scan) {
  py::array_t<double> out(static_cast<py::ssize_t>(scan.ranges.size()));
  std::copy(scan.ranges.begin(), scan.ranges.end(), out.mutable_data());
  return out;
}

std::vector<double> ranges_from(const py::array_t<double, py::array::c_style | py::array::forcecast>& ranges) {
  if (ranges.ndim() != 1) throw py::value_error("ranges must be a 1-D array");
  return {ranges.data(), ranges.data() + ranges.size()};
}

/// One message of a log as a dict: kind "scan" (scan, odom or None, type), "odometry" (stamp,
/// pose, tv, rv), "imu" (stamp, roll, pitch, yaw_rate), "true_pose" (stamp, pose, odom).
py::dict message_dict(const SensorMessage& message) {
  py::dict out;
  if (const auto* laser = std::get_if<LaserMessage>(&message)) {
    out["kind"] = "scan";
    out["scan"] = laser->scan;
    out["odom"] = laser->has_poses ? py::cast(laser->odom_pose) : py::none();
    out["type"] = laser->type;
  } else if (const auto* odometry = std::get_if<OdometryMessage>(&message)) {
    out["kind"] = "odometry";
    out["stamp"] = odometry->reading.stamp;
    out["pose"] = odometry->reading.pose;
    out["tv"] = odometry->reading.tv;
    out["rv"] = odometry->reading.rv;
  } else if (const auto* imu = std::get_if<ImuMessage>(&message)) {
    out["kind"] = "imu";
    out["stamp"] = imu->reading.stamp;
    out["roll"] = imu->reading.roll;
    out["pitch"] = imu->reading.pitch;
    out["yaw_rate"] = imu->reading.yaw_rate;
  } else {
    const auto& truth = std::get<TruePoseMessage>(message);
    out["kind"] = "true_pose";
    out["stamp"] = truth.stamp;
    out["pose"] = truth.true_pose;
    out["odom"] = truth.odom_pose;
  }
  return out;
}

/// Each SLAM method with its configuration from a preset file (empty: the defaults).
template <typename Config>
Config method_config(const std::string& preset, const std::string& method) {
  return read_method_preset(preset, method, Config{});
}

}  // namespace
}  // namespace slam2d

PYBIND11_MODULE(_slam2d, m) {
  using namespace slam2d;
  m.doc() = "slam2d: 2D LiDAR scan matching, SLAM, localization and evaluation (C++ library)";
  py::register_exception<Error>(m, "Error", PyExc_RuntimeError);

  py::class_<SE2>(m, "SE2", "A rigid motion in the plane: rotation theta, then translation (x, y)")
      .def(py::init<>())
      .def(py::init<double, double, double>(), py::arg("x"), py::arg("y"), py::arg("theta"))
      .def_property_readonly("x", &SE2::x)
      .def_property_readonly("y", &SE2::y)
      .def_property_readonly("theta", &SE2::theta)
      .def("matrix", &SE2::matrix, "The 3 x 3 homogeneous matrix")
      .def("vector", &SE2::vector, "(x, y, theta)")
      .def("inverse", [](const SE2& p) { return p.inverse(); })
      .def("log", [](const SE2& p) { return p.log(); }, "The tangent vector (v_x, v_y, omega)")
      .def_static("exp", [](const Eigen::Vector3d& xi) { return SE2::exp(xi); }, py::arg("xi"))
      .def("__mul__", [](const SE2& a, const SE2& b) { return a * b; }, py::is_operator())
      .def("__mul__", [](const SE2& a, const Eigen::Vector2d& p) -> Eigen::Vector2d { return a * p; }, py::is_operator())
      .def("__eq__", [](const SE2& a, const SE2& b) { return a == b; }, py::is_operator())
      .def("__repr__", [](const SE2& p) {
        return "SE2(x=" + std::to_string(p.x()) + ", y=" + std::to_string(p.y()) + ", theta=" + std::to_string(p.theta()) + ")";
      })
      .def(py::pickle([](const SE2& p) { return py::make_tuple(p.x(), p.y(), p.theta()); },
                      [](const py::tuple& t) { return SE2(t[0].cast<double>(), t[1].cast<double>(), t[2].cast<double>()); }));

  py::class_<MatchResult>(m, "MatchResult", "A scan matcher's estimate of T_target_source")
      .def_readonly("pose", &MatchResult::T_target_source)
      .def_readonly("covariance", &MatchResult::covariance)
      .def_readonly("converged", &MatchResult::converged)
      .def_readonly("iterations", &MatchResult::iterations)
      .def_readonly("inliers", &MatchResult::inliers)
      .def_readonly("residual", &MatchResult::residual)
      .def_readonly("degenerate", &MatchResult::degenerate)
      .def_readonly("weak_direction", &MatchResult::weak_direction)
      .def("information", &MatchResult::information);

  py::class_<LaserScan>(m, "Scan", "One sweep of a planar range finder (sensor_msgs/LaserScan's fields)")
      .def(py::init([](const py::array_t<double, py::array::c_style | py::array::forcecast>& ranges, double angle_min,
                       double angle_increment, double range_max, double range_min, double stamp, const SE2& mounting) {
             LaserScan scan;
             scan.ranges = ranges_from(ranges);
             scan.angle_min = angle_min;
             scan.angle_increment = angle_increment;
             scan.range_max = range_max;
             scan.range_min = range_min;
             scan.stamp = stamp;
             scan.T_robot_sensor = mounting;
             return scan;
           }),
           py::arg("ranges"), py::arg("angle_min"), py::arg("angle_increment"), py::arg("range_max"),
           py::arg("range_min") = 0.0, py::arg("stamp") = 0.0, py::arg("T_robot_sensor") = SE2())
      .def_property("ranges", &ranges_array, [](LaserScan& scan, const py::array_t<double, py::array::c_style | py::array::forcecast>& r) {
        scan.ranges = ranges_from(r);
      })
      .def_readwrite("stamp", &LaserScan::stamp)
      .def_readwrite("angle_min", &LaserScan::angle_min)
      .def_readwrite("angle_increment", &LaserScan::angle_increment)
      .def_readwrite("range_min", &LaserScan::range_min)
      .def_readwrite("range_max", &LaserScan::range_max)
      .def_readwrite("T_robot_sensor", &LaserScan::T_robot_sensor)
      .def("points", [](const LaserScan& scan, bool robot_frame) {
        return points_array(to_point_cloud(scan, robot_frame ? ScanFrame::kRobot : ScanFrame::kSensor).cloud);
      }, py::arg("robot_frame") = true, "The valid beams' end points, N x 2, in the robot (or sensor) frame");

  py::class_<LogReader>(m, "LogReader", "A log (CARMEN, ROS 1 bag, MCAP, rosbag2) as an iterator of messages")
      .def(py::init([](const std::string& path, const std::string& scan_topic, const std::string& odom_topic,
                       std::optional<double> fov_deg) {
             LogReaderOptions options;
             options.bag.scan_topic = scan_topic;
             options.bag.odom_topic = odom_topic;
             if (fov_deg) options.carmen.geometry.field_of_view = deg_to_rad(*fov_deg);
             return std::make_unique<LogReader>(path, options);
           }),
           py::arg("path"), py::arg("scan_topic") = "", py::arg("odom_topic") = "", py::arg("fov_deg") = py::none())
      .def("__iter__", [](LogReader& reader) -> LogReader& { return reader; })
      .def("__next__", [](LogReader& reader) {
        std::optional<SensorMessage> message = reader.next();
        if (!message) throw py::stop_iteration();
        return message_dict(*message);
      })
      .def_property_readonly("format", [](const LogReader& reader) { return std::string(log_format_name(reader.format())); })
      .def_property_readonly("progress", &LogReader::progress);

  py::class_<GraphSlam>(m, "GraphSlam", "Graph SLAM, one scan at a time (configs/graph.yaml's fields)")
      .def(py::init([](const std::string& preset) { return GraphSlam(method_config<GraphSlamConfig>(preset, "graph")); }),
           py::arg("preset") = "")
      .def("add_scan", [](GraphSlam& slam, const LaserScan& scan, std::optional<SE2> odom) {
        py::gil_scoped_release release;
        return slam.add_scan(scan, odom).T_map_robot;
      }, py::arg("scan"), py::arg("odom") = py::none())
      .def("finish", [](GraphSlam& slam) {
        py::gil_scoped_release release;
        slam.finish();
      })
      .def_property_readonly("trajectory", [](const GraphSlam& slam) { return trajectory_array(slam.trajectory()); })
      .def_property_readonly("map", [](const GraphSlam& slam) { return map_dict(slam.map()); });

  py::class_<HectorSlam>(m, "HectorSlam", "Hector SLAM, one scan at a time (configs/hector.yaml's fields)")
      .def(py::init([](const std::string& preset) { return std::make_unique<HectorSlam>(method_config<HectorSlamConfig>(preset, "hector")); }),
           py::arg("preset") = "")
      .def("add_scan", [](HectorSlam& slam, const LaserScan& scan, std::optional<SE2> odom) {
        py::gil_scoped_release release;
        HectorInputs inputs;
        inputs.T_odom_robot = odom;
        return slam.add_scan(scan, inputs).T_map_robot;
      }, py::arg("scan"), py::arg("odom") = py::none())
      .def("finish", [](HectorSlam&) {})
      .def_property_readonly("trajectory", [](const HectorSlam& slam) { return trajectory_array(slam.trajectory()); })
      .def_property_readonly("map", [](const HectorSlam& slam) { return map_dict(slam.occupancy_map()); });

  py::class_<RbpfSlam>(m, "RbpfSlam", "The Rao-Blackwellized particle filter, one scan at a time (configs/rbpf.yaml's fields)")
      .def(py::init([](const std::string& preset) { return std::make_unique<RbpfSlam>(method_config<RbpfConfig>(preset, "rbpf")); }),
           py::arg("preset") = "")
      .def("add_scan", [](RbpfSlam& slam, const LaserScan& scan, std::optional<SE2> odom) {
        if (!odom) throw py::value_error("the particle filter needs the odometry pose at each scan");
        py::gil_scoped_release release;
        return slam.add_scan(scan, *odom).T_map_robot;
      }, py::arg("scan"), py::arg("odom") = py::none())
      .def("finish", [](RbpfSlam&) {})
      .def_property_readonly("trajectory", [](const RbpfSlam& slam) { return trajectory_array(slam.trajectory()); })
      .def_property_readonly("map", [](const RbpfSlam& slam) { return map_dict(slam.occupancy_map()); });

  // A localizer in a known map, with the map it reads (the session follows the robot through
  // odometry stalls, as `slam2d localize` does).
  struct PyLocalizer {
    LocalizationMap map;
    std::unique_ptr<Localizer> localizer;
    std::unique_ptr<LocalizationSession> session;
  };
  py::class_<PyLocalizer>(m, "Localizer", "Localization in a known map (markov, ekf, mcl, hybrid), one scan at a time")
      .def(py::init([](const std::string& map_yaml, const std::string& method, std::optional<SE2> initial,
                       const Eigen::Vector3d& sigma, const std::string& preset, std::optional<std::size_t> particles,
                       std::optional<std::uint64_t> seed) {
             auto out = std::make_unique<PyLocalizer>(PyLocalizer{LocalizationMap(read_map(map_yaml)), nullptr, nullptr});
             cli::LocalizeOptions options;
             options.method = method;
             options.global = !initial.has_value();
             if (initial) {
               options.initial = fmt::format("{},{},{}", initial->x(), initial->y(), initial->theta());
               options.initial_sigma = fmt::format("{},{},{}", sigma.x(), sigma.y(), sigma.z());
             }
             options.config = preset;
             options.particles = particles;
             options.seed = seed;
             cli::JsonObject settings;
             out->localizer = cli::make_localizer(options, out->map, settings);
             out->session = std::make_unique<LocalizationSession>(*out->localizer, std::nullopt, OdometryGuardConfig{}, &out->map);
             return out;
           }),
           py::arg("map"), py::arg("method") = "mcl", py::arg("initial") = py::none(),
           py::arg("sigma") = Eigen::Vector3d(0.3, 0.3, 0.2), py::arg("preset") = "", py::arg("particles") = py::none(),
           py::arg("seed") = py::none())
      .def("update", [](PyLocalizer& self, const SE2& odom, const LaserScan& scan) {
        LocalizationEstimate estimate;
        {
          py::gil_scoped_release release;
          estimate = self.session->add(odom, scan);
        }
        py::dict out;
        out["pose"] = estimate.pose;
        out["covariance"] = estimate.covariance;
        out["localized"] = estimate.localized;
        return out;
      }, py::arg("odom"), py::arg("scan"), "One step: the odometry pose at the scan and the scan; the estimate")
      .def_property_readonly("trajectory", [](const PyLocalizer& self) { return trajectory_array(self.session->trajectory()); });

  m.def("method_names", &method_names, "The SLAM and localization methods with a configuration");
  m.def("default_preset", &default_preset, py::arg("name"), "A method's or matcher's defaults as a preset (YAML)");
  m.def("matcher_names", &matcher_names, "Every scan matcher slam2d knows, by name");
  py::class_<PointCloud2>(m, "Cloud",
                          "A point cloud in slam2d's own memory: made once from N x 2 points, then matched "
                          "any number of times without another copy")
      .def(py::init([](const Points& points) { return cloud_from(points, "points"); }), py::arg("points"))
      .def("__len__", &PointCloud2::size)
      .def("points", &points_array);

  const auto match_clouds = [](const PointCloud2& target, const PointCloud2& source, const SE2& guess,
                               const std::string& method, const std::string& config) {
    const Matcher matcher = config.empty() ? make_matcher(method) : make_matcher(method, ConfigNode::parse(config, "config"));
    py::gil_scoped_release release;
    return matcher(target, source, guess);
  };
  m.def("match_clouds", match_clouds, py::arg("target"), py::arg("source"), py::arg("guess"), py::arg("method"),
        py::arg("config") = "", "Matches `source` to `target` (Clouds) from `guess`; `config` is YAML (or JSON)");
  m.def(
      "match",
      [match_clouds](const Points& target, const Points& source, const SE2& guess, const std::string& method,
                     const std::string& config) {
        return match_clouds(cloud_from(target, "target"), cloud_from(source, "source"), guess, method, config);
      },
      py::arg("target"), py::arg("source"), py::arg("guess"), py::arg("method"), py::arg("config") = "",
      "Matches `source` to `target` (N x 2 points) from `guess`; `config` is YAML (or JSON) of the matcher's fields");

  m.def(
      "_time_match",
      [](const Points& target, const Points& source, const SE2& guess, const std::string& method, int repeats) {
        // The same match looped in C++ (clouds and matcher made once): what slam2d.match's
        // per-call overhead is measured against (bench/python/python_overhead.py).
        const PointCloud2 target_cloud = cloud_from(target, "target");
        const PointCloud2 source_cloud = cloud_from(source, "source");
        const Matcher matcher = make_matcher(method);
        py::gil_scoped_release release;
        const auto start = std::chrono::steady_clock::now();
        for (int i = 0; i < repeats; ++i) matcher(target_cloud, source_cloud, guess);
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() / std::max(repeats, 1);
      },
      py::arg("target"), py::arg("source"), py::arg("guess"), py::arg("method"), py::arg("repeats"),
      "Seconds per call of the matcher looped in C++ (for the overhead benchmark)");

  m.def(
      "map_log",
      [](const std::string& log, const std::string& method, const std::string& out_dir, const std::string& config,
         std::optional<std::uint64_t> seed, std::optional<double> resolution, bool no_odometry, const std::string& frame,
         const std::string& odometry_source, std::optional<double> scan_rate, bool odometry_smoothing) {
        cli::MapJobOptions options;
        options.log = log;
        options.method = method;
        options.out_dir = out_dir;
        options.config = config;
        options.seed = seed;
        options.resolution = resolution;
        options.no_odometry = no_odometry;
        options.trajectory_frame = frame;
        options.odometry_source = odometry_source;
        options.scan_rate = scan_rate;
        options.odometry_smoothing = odometry_smoothing;
        options.quiet = true;
        cli::MapJobResult result;
        {
          py::gil_scoped_release release;
          result = cli::run_map_job(options);
        }
        py::dict out;
        out["trajectory"] = trajectory_array(result.trajectory);
        out["map"] = map_dict(result.map);
        out["summary"] = result.summary.dump();
        return out;
      },
      py::arg("log"), py::arg("method"), py::arg("out_dir"), py::arg("config") = "", py::arg("seed") = py::none(),
      py::arg("resolution") = py::none(), py::arg("no_odometry") = false, py::arg("trajectory_frame") = "robot",
      py::arg("odometry_source") = "log", py::arg("scan_rate") = py::none(), py::arg("odometry_smoothing") = true,
      "Runs `slam2d map` on a log (CARMEN or bag) and writes its outputs into out_dir");

  m.def(
      "relation_error",
      [](const Points& trajectory, const std::string& relations_path) {
        const Trajectory estimate = trajectory_from(trajectory);
        const std::vector<Relation> relations = read_relations(relations_path);
        RelationErrorResult result;
        {
          py::gil_scoped_release release;
          result = relation_error(estimate, relations);
        }
        py::dict out;
        out["relations"] = result.relations;
        out["missing"] = result.missing;
        out["trans_mean"] = result.translation.mean;
        out["trans_std"] = result.translation.std;
        out["rot_mean_deg"] = result.rotation_deg.mean;
        return out;
      },
      py::arg("trajectory"), py::arg("relations"), "Kuemmerle et al. 2009 relation error of an N x 4 trajectory");
}
