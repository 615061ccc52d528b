// Writes the seed corpora of the fuzz targets (tests/fuzz/corpus/<target>/) from the project's own
// encoders: messages of a small synthetic world through the object-map engine, a tiny model, the
// object map's own save files, a log of those messages, the shipped config files, small images
// and dataset folders. Usage: fuzz-make-seeds SOURCE_DIR OUT_DIR (scripts/fuzz-seeds).
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <lcm/lcm-cpp.hpp>
#include <opencv2/core.hpp>
#include <random>
#include <string>
#include <vector>

#include "common/bus/image_msg.h"
#include "common/image_codec.h"
#include "procs/objectmap/map_store.h"
#include "procs/objectmap/object_map.h"
#include "procs/recognizer/model.h"
#include "slamaware/keyframe_t.hpp"
#include "slamaware/proc_command_t.hpp"
#include "slamaware/proc_status_t.hpp"
#include "slamaware/status_t.hpp"
#include "tests/fuzz/fuzz_support.h"
#include "tests/objectmap/synthetic_world.h"

namespace fs = std::filesystem;
using namespace slamaware;
using namespace slamaware::objectmap;
using namespace slamaware::recognizer;

namespace {

std::string out_dir;

void seed(const std::string& target, const std::string& name, const std::string& bytes) {
  fuzz::writeFile(out_dir + "/" + target + "/" + name, bytes);
}
std::string byteString(uint8_t b) { return std::string(1, static_cast<char>(b)); }
std::string readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

template <class Msg>
std::string encoded(const Msg& m) {
  std::string out(static_cast<size_t>(m.getEncodedSize()), '\0');
  m.encode(out.data(), 0, static_cast<int>(out.size()));
  return out;
}

// The order of fuzz_messages.cpp's kDecoders.
enum TypeIndex : uint8_t {
  kBox,
  kCameraInfo,
  kDetections,
  kImage,
  kKeyframe,
  kObjectDetections,
  kObjectMap,
  kQueryReply,
  kQuery,
  kObject,
  kPointCloud,
  kPose,
  kProcCommand,
  kProcInfo,
  kProcStatus,
  kProposals,
  kStatus
};

struct LoggedMessage {
  std::string channel, bytes;
};

// A log of those messages (lcm-logger's format).
void seedLog(const std::vector<LoggedMessage>& log) {
  const std::string path = out_dir + "/session.lcm.tmp";
  {
    lcm::LogFile file(path, "w");
    int64_t t = 1000000;
    for (const auto& m : log) {
      lcm::LogEvent ev{};
      ev.timestamp = t += 33333;
      ev.channel = m.channel;
      ev.datalen = static_cast<int32_t>(m.bytes.size());
      ev.data = const_cast<char*>(m.bytes.data());
      file.writeEvent(&ev);
    }
  }
  seed("fuzz_log_reader", "session", readAll(path));
  fs::remove(path);
}

// The object map's own save of that world.
void seedMapStore(const ObjectMapEngine& engine) {
  const std::string dir = out_dir + "/map.tmp";
  MapStore(dir).save(engine.snapshot());
  std::string content, ot;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (name.size() > 5 && name.substr(name.size() - 5) == ".json") content = readAll(e.path());
    if (name.size() > 3 && name.substr(name.size() - 3) == ".ot") ot = readAll(e.path());
  }
  seed("fuzz_map_store", "files", byteString(0) + fuzz::joinParts({content, ot}));
  const size_t begin = content.find("\n\"content\":") + 11;
  seed("fuzz_map_store", "content",
       byteString(1) + fuzz::joinParts({content.substr(begin, content.size() - begin - 2), ot}));
  fs::remove_all(dir);
}

// A tiny model that passes every check: 2 PCA dimensions, 2 codewords, 2 shape bins, 2 classes.
void seedModel() {
  RecognizerModel m;
  m.params.pca_dims = 2;
  m.params.vocabulary_size = 2;
  m.params.shape_bins = 2;
  std::mt19937 rng(1);
  std::normal_distribution<float> g;
  m.pca.mean = Eigen::RowVectorXf::NullaryExpr(kFeatureDims, [&] { return g(rng); });
  m.pca.basis = Eigen::MatrixXf::NullaryExpr(kFeatureDims, 2, [&] { return g(rng); });
  m.pca.variance = Eigen::VectorXf::Ones(2);
  m.vocabulary.centers = MatrixRM::NullaryExpr(2, 2, [&] { return g(rng); });
  m.classifier.classes = {"mug", "background"};
  m.classifier.weights = MatrixRM::NullaryExpr(2, m.params.encodedDims(), [&] { return g(rng); });
  m.classifier.bias = Eigen::VectorXf::Zero(2);
  m.classifier.uniform_mix = 0.1f;
  m.provenance = "{\"seed\":true}";
  const std::string path = out_dir + "/tiny.model.tmp";
  saveModel(m, path);
  const std::string file = readAll(path);
  fs::remove(path);
  seed("fuzz_model", "file", byteString(0) + file);
  seed("fuzz_model", "payload", byteString(1) + file.substr(28));
}

// The shipped configs, each for its loader (fuzz_config.cpp's order), and a sequence.yaml.
void seedConfigs(const std::string& source) {
  const std::vector<std::pair<std::string, uint8_t>> configs = {
      {"system.yaml", 0},        {"system.yaml", 1},
      {"camera.yaml", 2},        {"slam.yaml", 3},
      {"proposals.yaml", 4},     {"recognizer.yaml", 5},
      {"objectmap.yaml", 6},     {"train-quick.yaml", 7},
      {"scenes/sample.yaml", 8}, {"objects/apple_ball.yaml", 9}};
  for (const auto& [file, loader] : configs) {
    std::string name = file;
    std::replace(name.begin(), name.end(), '/', '_');
    seed("fuzz_config", std::to_string(loader) + "_" + name,
         byteString(loader) + readAll(source + "/config/" + file));
  }
  seed("fuzz_config", "10_sequence.yaml",
       byteString(10) +
           "name: s\nsource: camera\nfps: 30\nframes: 2\ncamera:\n  width: 640\n  height: 480\n"
           "  fx: 525\n  fy: 525\n  cx: 319.5\n  cy: 239.5\n  distortion: [0, 0, 0, 0, 0]\n"
           "classes: [bowl, cap]\n");
}

// Dataset folders: a sequence (its sequence.yaml as seeded for fuzz_config) and an object set.
void seedDatasets() {
  const std::string sequence_yaml = readAll(out_dir + "/fuzz_config/10_sequence.yaml").substr(1);
  seed("fuzz_datasets", "sequence",
       byteString(0) +
           fuzz::joinParts({sequence_yaml,
                            "frame,x,y,w,h,class,instance\n0,10,20,30,40,bowl,bowl_1\n",
                            "instance,class,cx,cy,cz,sx,sy,sz\nbowl_1,bowl,0,0,1,0.1,0.1,0.05\n",
                            "0.0 0 0 0 0 0 0 1\n0.033 0.01 0 0 0 0 0 1\n", "0 0.0\n1 0.033\n",
                            "000000.png\n000001.png\n"}));
  seed("fuzz_datasets", "object_set",
       byteString(1) +
           fuzz::joinParts({"source: synth\n",
                            "bowl/bowl_1/bowl_1_1_1_crop.png\nbowl/bowl_1/bowl_1_1_1_maskcrop.png\n"
                            "bowl/bowl_1/bowl_1_1_1_loc.txt\nmug/mug_2/mug_2_2_5_crop.png\n",
                            "", "", "120,88\n", ""}));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: fuzz-make-seeds SOURCE_DIR OUT_DIR\n");
    return 2;
  }
  const std::string source = argv[1];
  out_dir = argv[2];
  std::vector<LoggedMessage> log;
  auto message = [&](TypeIndex type, const std::string& name, const std::string& channel,
                     const std::string& bytes) {
    seed("fuzz_messages", name, byteString(type) + bytes);
    log.push_back({channel, bytes});
  };

  // A small world through the object map, as the pipeline would send it.
  test::SyntheticWorldOptions wo;
  wo.frames = 6;
  wo.keyframes = 2;
  wo.wall = false;
  wo.table = false;
  wo.spacing = 0.02;
  const test::SyntheticWorld world(wo, test::SyntheticWorld::defaultObjects());
  ObjectMapOptions map_options;
  map_options.occupancy.resolution = 0.04;  // a small .ot file
  ObjectMapEngine engine{map_options};
  std::string why;
  engine.onCameraInfo(world.cameraInfo(), &why);
  message(kCameraInfo, "camera_info", "CAMERA_INFO", encoded(world.cameraInfo()));
  const auto clouds = world.keyframeClouds(1);
  for (const auto& c : clouds) engine.onMap(c, &why);
  message(kPointCloud, "point_cloud", "SLAM_MAP", encoded(clouds.front()));
  object_detections_t last_fused{};
  for (int f = 0; f < wo.frames; ++f) {
    const pose_t pose = world.poseMessage(f, 1);
    const proposals_t proposals = world.proposals(f, 1);
    const detections_t detections = world.detections(f, 1);
    engine.onPose(pose, &why);
    engine.onProposals(proposals, &why);
    engine.onDetections(detections, &why);
    last_fused = engine.frameDetections(detections);
    if (f == wo.frames - 1) {
      message(kPose, "pose", "SLAM_POSE", encoded(pose));
      message(kProposals, "proposals", "PROPOSALS", encoded(proposals));
      message(kDetections, "detections", "DETECTIONS", encoded(detections));
      message(kObjectDetections, "object_detections", "OBJECT_DETECTIONS", encoded(last_fused));
    }
  }
  const object_map_t map = engine.objectMap();
  message(kObjectMap, "object_map", "OBJECT_MAP", encoded(map));
  if (!map.objects.empty()) message(kObject, "object", "OBJECT", encoded(map.objects.front()));
  if (!last_fused.boxes.empty()) message(kBox, "box", "BOX", encoded(last_fused.boxes.front()));
  object_query_t query{};
  query.request_id = 7;
  query.kind = object_query_t::KIND_BY_LABEL;
  query.label = "bowl";
  query.map_id = -1;
  message(kQuery, "query", "OBJECT_QUERY", encoded(query));
  message(kQueryReply, "query_reply", "OBJECT_QUERY_REPLY", encoded(engine.answer(query)));
  message(kKeyframe, "keyframe", "SLAM_KEYFRAME", encoded(keyframe_t{}));
  message(kProcCommand, "proc_command", "PROC_COMMAND", encoded(proc_command_t{}));
  message(kProcInfo, "proc_info", "PROC_INFO", encoded(proc_info_t{}));
  message(kProcStatus, "proc_status", "PROC_STATUS", encoded(proc_status_t{}));
  message(kStatus, "status", "SLAM_STATUS", encoded(status_t{}));
  cv::Mat image(12, 16, CV_8UC3);
  cv::randu(image, 0, 255);
  message(kImage, "image_jpeg", "CAMERA",
          encoded(makeImageMessage(image, 1000000, 0, image_t::PIXEL_FORMAT_JPEG)));
  message(kImage, "image_rgb8", "CAMERA",
          encoded(makeImageMessage(image, 1033333, 1, image_t::PIXEL_FORMAT_RGB8)));
  message(kImage, "image_gray8", "CAMERA",
          encoded(makeImageMessage(image, 1066666, 2, image_t::PIXEL_FORMAT_GRAY8)));

  seedLog(log);
  seedMapStore(engine);
  seedModel();
  seedConfigs(source);
  seed(
      "fuzz_image", "jpeg", byteString(0) + [&] {
        const auto b = encodeJpeg(image, 80);
        return std::string(b.begin(), b.end());
      }());
  seed(
      "fuzz_image", "png", byteString(1) + [&] {
        const auto b = encodePng(image);
        return std::string(b.begin(), b.end());
      }());

  seedDatasets();

  std::printf("seeds written to %s\n", out_dir.c_str());
  return 0;
}
