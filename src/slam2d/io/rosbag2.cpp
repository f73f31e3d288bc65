// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/io/rosbag2.hpp"

#include <sqlite3.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <utility>
#include <vector>

#include "slam2d/core/error.hpp"
#include "slam2d/io/config_file.hpp"
#include "slam2d/io/detail/cdr.hpp"
#include "slam2d/io/mcap.hpp"

namespace slam2d {
namespace {

namespace fs = std::filesystem;

/// rosbag2's sqlite3 storage (Humble layout; later schemas only add tables and columns).
class SqliteSource final : public BagSource {
 public:
  explicit SqliteSource(std::string path) : path_(std::move(path)) {
    std::error_code error;
    if (!fs::is_regular_file(path_, error)) throw Error(path_ + ": cannot open: no such file");
    if (sqlite3_open_v2(path_.c_str(), &db_, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
      const std::string reason = db_ ? sqlite3_errmsg(db_) : "out of memory";
      sqlite3_close(db_);
      throw Error(path_ + ": cannot open: " + reason);
    }
    try {
      read_topics();
      statement_ = prepare("SELECT id, topic_id, timestamp, data FROM messages ORDER BY timestamp, id");
    } catch (...) {
      sqlite3_finalize(statement_);
      sqlite3_close(db_);
      throw;
    }
  }
  ~SqliteSource() override {
    sqlite3_finalize(statement_);
    sqlite3_close(db_);
  }
  SqliteSource(const SqliteSource&) = delete;
  SqliteSource& operator=(const SqliteSource&) = delete;

  const std::string& path() const override { return path_; }
  const std::vector<BagTopic>& topics() const override { return topics_; }
  double progress() const override {
    return total_ == 0 ? 1.0 : std::min(1.0, static_cast<double>(read_) / static_cast<double>(total_));
  }

  std::optional<DecodedRecord> next(const std::vector<std::string>& wanted) override {
    if (!selected_ || wanted != wanted_) select(wanted);
    while (!done_) {
      const int status = sqlite3_step(statement_);
      if (status == SQLITE_DONE) {
        done_ = true;
        break;
      }
      if (status != SQLITE_ROW) fail("reading messages");
      ++read_;
      const auto row = topic_rows_.find(sqlite3_column_int64(statement_, 1));
      if (row == topic_rows_.end()) {
        throw Error(path_ + ": message " + std::to_string(sqlite3_column_int64(statement_, 0)) + " has topic_id " +
                    std::to_string(sqlite3_column_int64(statement_, 1)) + ", which is not in the topics table");
      }
      const std::optional<detail::Ros2Type>& type = topic_types_[row->second];
      if (!type) continue;
      const sqlite3_int64 id = sqlite3_column_int64(statement_, 0);
      const sqlite3_int64 timestamp = sqlite3_column_int64(statement_, 2);
      if (timestamp < 0) throw Error(path_ + ": message " + std::to_string(id) + " has a negative timestamp");
      const auto* data = static_cast<const std::uint8_t*>(sqlite3_column_blob(statement_, 3));
      const int size = sqlite3_column_bytes(statement_, 3);
      return detail::decode_record(path_, topics_[row->second].name, *type, static_cast<std::uint64_t>(timestamp),
                                   static_cast<std::size_t>(id), data, static_cast<std::size_t>(size));
    }
    return std::nullopt;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw Error(path_ + ": sqlite3: " + what + ": " + sqlite3_errmsg(db_));
  }

  sqlite3_stmt* prepare(const char* sql) {
    sqlite3_stmt* statement = nullptr;
    if (sqlite3_prepare_v2(db_, sql, -1, &statement, nullptr) != SQLITE_OK) {
      fail("not a rosbag2 database (" + std::string(sql) + ")");
    }
    return statement;
  }

  void read_topics() {
    sqlite3_stmt* statement = prepare("SELECT id, name, type, serialization_format FROM topics ORDER BY id");
    auto text = [&](int column) {
      const unsigned char* value = sqlite3_column_text(statement, column);
      return value ? std::string(reinterpret_cast<const char*>(value)) : std::string();
    };
    int status;
    while ((status = sqlite3_step(statement)) == SQLITE_ROW) {
      topic_rows_[sqlite3_column_int64(statement, 0)] = topics_.size();
      topics_.push_back(BagTopic{text(1), text(2), 0, 0.0, 0.0});
      encodings_.push_back(text(3));
    }
    sqlite3_finalize(statement);
    if (status != SQLITE_DONE) fail("reading the topics");

    statement = prepare("SELECT topic_id, COUNT(*), MIN(timestamp), MAX(timestamp) FROM messages GROUP BY topic_id");
    while ((status = sqlite3_step(statement)) == SQLITE_ROW) {
      const auto row = topic_rows_.find(sqlite3_column_int64(statement, 0));
      if (row == topic_rows_.end()) continue;  // reported by next() when it reaches such a message
      BagTopic& topic = topics_[row->second];
      topic.count = static_cast<std::size_t>(sqlite3_column_int64(statement, 1));
      topic.first_stamp = detail::nanoseconds_to_seconds(static_cast<std::uint64_t>(std::max<sqlite3_int64>(0, sqlite3_column_int64(statement, 2))));
      topic.last_stamp = detail::nanoseconds_to_seconds(static_cast<std::uint64_t>(std::max<sqlite3_int64>(0, sqlite3_column_int64(statement, 3))));
      total_ += topic.count;
    }
    sqlite3_finalize(statement);
    if (status != SQLITE_DONE) fail("counting the messages");
  }

  void select(const std::vector<std::string>& wanted) {
    wanted_ = wanted;
    selected_ = true;
    topic_types_.assign(topics_.size(), std::nullopt);
    for (std::size_t i = 0; i < topics_.size(); ++i) {
      if (std::find(wanted.begin(), wanted.end(), topics_[i].name) == wanted.end()) continue;
      topic_types_[i] = detail::wanted_type(path_, topics_[i].name, topics_[i].type, encodings_[i]);
    }
  }

  std::string path_;
  sqlite3* db_ = nullptr;
  sqlite3_stmt* statement_ = nullptr;
  std::vector<BagTopic> topics_;
  std::vector<std::string> encodings_;                    // serialization_format, per topic
  std::map<sqlite3_int64, std::size_t> topic_rows_;       // topics.id -> index in topics_
  std::vector<std::optional<detail::Ros2Type>> topic_types_;
  std::vector<std::string> wanted_;
  bool selected_ = false;
  bool done_ = false;
  std::size_t total_ = 0;
  std::size_t read_ = 0;
};

fs::path metadata_path(const std::string& path) {
  const fs::path p(path);
  std::error_code error;
  return fs::is_directory(p, error) ? p / "metadata.yaml" : p;
}

}  // namespace

bool is_rosbag2(const std::string& path) {
  std::error_code error;
  const fs::path p(path);
  if (fs::is_directory(p, error)) return fs::is_regular_file(p / "metadata.yaml", error);
  return p.filename() == "metadata.yaml" && fs::is_regular_file(p, error);
}

std::unique_ptr<BagSource> open_rosbag2(const std::string& path) {
  const fs::path metadata = metadata_path(path);
  const std::string name = metadata.string();
  std::error_code error;
  if (!fs::is_regular_file(metadata, error)) throw Error(name + ": cannot open: no such file (not a rosbag2 folder?)");
  const ConfigNode info = ConfigNode::load(name).at("rosbag2_bagfile_information");
  const std::string storage = info.at("storage_identifier").as_string();
  std::vector<std::string> files;
  for (const ConfigNode& item : info.at("relative_file_paths").items()) files.push_back(item.as_string());
  if (files.size() != 1) {
    throw Error(name + ": " + std::to_string(files.size()) +
                " storage files in relative_file_paths; slam2d reads a bag of exactly one (split bags are not supported)");
  }
  const fs::path file = metadata.parent_path() / files.front();
  if (!fs::is_regular_file(file, error)) throw Error(name + ": storage file " + file.string() + " does not exist");
  if (storage == "mcap") return open_mcap(file.string());
  if (storage == "sqlite3") return open_rosbag2_sqlite(file.string());
  throw Error(name + ": unknown storage_identifier '" + storage + "' (slam2d reads mcap and sqlite3)");
}

std::unique_ptr<BagSource> open_rosbag2_sqlite(const std::string& db3_path) {
  return std::make_unique<SqliteSource>(db3_path);
}

}  // namespace slam2d
