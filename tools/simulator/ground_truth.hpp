// simulator/ground_truth: the per-frame reference of every vehicle in view.
//
// Contract (definitions, also in docs/simulator.md):
//  - in view: at least one sample of the vehicle's silhouette (its triangles rasterized
//    alone on the renderer's sample grid) maps into the image;
//  - image box: the rectangle whose length axis is the vehicle's driving direction as seen
//    in the image (the direction from the projected vehicle-frame origin to the projection of
//    a point 1 m ahead of it on the road) and which encloses the projections of every vertex
//    of the rendered model (the 36 ASM keypoints and the wheel cylinders; the whole mesh for
//    large vehicles). It is not clipped to the image;
//  - truncation: share of the silhouette samples that fall outside the image;
//  - occlusion: share of the in-image silhouette samples whose visible surface belongs to
//    another object (tree, building, vehicle);
//  - keypoint pixel: the world keypoint projected with the recorded camera and pose through
//    lifting::Lifter::worldToPixel (so it matches the application's own projection); visible
//    when inside the image, one of the 2 x 2 samples around its ideal position shows this
//    vehicle at the keypoint's depth (within 0.15 m: not self-occluded, not hidden), and one
//    of the 2 x 2 output pixels around it shows this vehicle in the object-id image (so a
//    visible keypoint lies on the car as rendered, also at silhouette corners).
// Positions are the vehicle-frame origin (footprint centre on the road, ENU); heading is
// the driving direction; speed and yaw rate are those of the bicycle model (rear axle).
#pragma once

#include <cstdint>
#include <vector>

#include "lifting/lifting.hpp"
#include "renderer.hpp"
#include "sensor.hpp"
#include "sequence/recorded_sequence.hpp"
#include "traffic.hpp"
#include "world.hpp"

namespace vp::sim {

struct GroundTruthContext {
  const lifting::Lifter* lifter = nullptr;
  lifting::CameraPoseWorld pose{};
  const camera::CameraModel* camera = nullptr;
  const Renderer* renderer = nullptr;
  const Sensor* sensor = nullptr;
  const World* world = nullptr;
  PinholeView view{};            // the renderer's sample-grid pinhole
  const cv::Mat* ids = nullptr;  // output object ids (CV_32SC1)
};

// Appends the truth of the vehicles in view (objects, and 36 keypoints per car).
void computeGroundTruth(std::int64_t frameId, const std::vector<SimVehicle>& vehicles,
                        const GroundTruthContext& ctx, std::vector<sequence::ObjectTruth>& objects,
                        std::vector<sequence::KeypointTruth>& keypoints);

// The image box of a vehicle (definition above); false when the vehicle is behind the camera
// or outside the lens's valid field.
bool imageBox(const SimVehicle& vehicle, const GroundTruthContext& ctx, geometry::RotatedBox* box);

}  // namespace vp::sim
