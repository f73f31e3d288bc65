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

/// A bag split into several storage files (rosbag2 splits by size or duration): one bag, its
/// topics merged, its messages in receive-time order across the files (ties: the earlier file).
class SplitSource final : public BagSource {
 public:
  SplitSource(std::string path, std::vector<std::unique_ptr<BagSource>> files)
      : path_(std::move(path)), files_(std::move(files)), ahead_(files_.size()) {
    std::size_t before = 0;
    for (const auto& file : files_) {
      first_index_.push_back(before);
      for (const BagTopic& topic : file->topics()) {
        before += topic.count;
        auto same = std::find_if(topics_.begin(), topics_.end(), [&](const BagTopic& t) { return t.name == topic.name; });
        if (same == topics_.end()) {
          topics_.push_back(topic);
          continue;
        }
        check(same->type == topic.type, path_ + ": topic " + topic.name + " is " + same->type + " in one storage file and " +
                                            topic.type + " in " + file->path());
        if (topic.count == 0) continue;
        same->first_stamp = same->count == 0 ? topic.first_stamp : std::min(same->first_stamp, topic.first_stamp);
        same->last_stamp = same->count == 0 ? topic.last_stamp : std::max(same->last_stamp, topic.last_stamp);
        same->count += topic.count;
      }
    }
  }

  const std::string& path() const override { return path_; }
  const std::vector<BagTopic>& topics() const override { return topics_; }
  double progress() const override {
    double sum = 0.0;
    for (const auto& file : files_) sum += file->progress();
    return sum / static_cast<double>(files_.size());
  }

  std::vector<std::string> warnings() const override {
    std::vector<std::string> all;
    for (const auto& file : files_) {
      const std::vector<std::string> some = file->warnings();
      all.insert(all.end(), some.begin(), some.end());
    }
    return all;
  }

  std::optional<DecodedRecord> next(const std::vector<std::string>& wanted) override {
    std::optional<std::size_t> earliest;
    for (std::size_t i = 0; i < files_.size(); ++i) {
      if (ahead_[i] && std::find(wanted.begin(), wanted.end(), ahead_[i]->topic) == wanted.end()) ahead_[i].reset();
      if (!ahead_[i]) ahead_[i] = files_[i]->next(wanted);
      if (ahead_[i] && (!earliest || ahead_[i]->receive_time < ahead_[*earliest]->receive_time)) earliest = i;
    }
    if (!earliest) return std::nullopt;
    DecodedRecord record = std::move(*ahead_[*earliest]);
    ahead_[*earliest].reset();
    record.index += first_index_[*earliest];
    return record;
  }

 private:
  std::string path_;
  std::vector<std::unique_ptr<BagSource>> files_;
  std::vector<std::optional<DecodedRecord>> ahead_;  // each file's next wanted message
  std::vector<std::size_t> first_index_;             // messages in the files before each
  std::vector<BagTopic> topics_;
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
  if (storage != "mcap" && storage != "sqlite3") {
    throw Error(name + ": unknown storage_identifier '" + storage + "' (slam2d reads mcap and sqlite3)");
  }
  if (info.has("compression_mode") && !info.at("compression_mode").as_string().empty()) {
    throw Error(name + ": compression_mode " + info.at("compression_mode").as_string() +
                ": slam2d reads uncompressed rosbag2 storage (`ros2 bag convert` or `ros2 bag decompress` undoes it)");
  }
  std::vector<std::unique_ptr<BagSource>> files;
  for (const ConfigNode& item : info.at("relative_file_paths").items()) {
    const fs::path file = metadata.parent_path() / item.as_string();
    if (!fs::is_regular_file(file, error)) throw Error(name + ": storage file " + file.string() + " does not exist");
    files.push_back(storage == "mcap" ? open_mcap(file.string()) : open_rosbag2_sqlite(file.string()));
  }
  if (files.empty()) throw Error(name + ": no storage files in relative_file_paths");
  if (files.size() == 1) return std::move(files.front());
  return std::make_unique<SplitSource>(name, std::move(files));
}

std::unique_ptr<BagSource> open_rosbag2_sqlite(const std::string& db3_path) {
  return std::make_unique<SqliteSource>(db3_path);
}

}  // namespace slam2d
