// SPDX-License-Identifier: MIT
// Intel Embree 3, the peer of the ray and particles benches (built with IMPACT_HAVE_EMBREE), set
// up as Embree's tutorials do: one device, one scene of triangle geometries with float3 vertex and
// uint3 index buffers, RTC_BUILD_QUALITY_HIGH on the scene and on every geometry, and one
// rtcIntersect1 with a fresh RTCIntersectContext per ray (tnear 0, mask all, no time, no flags).
#pragma once

#include "impact/core/types.hpp"

#include <embree3/rtcore.h>

#include <cstddef>
#include <stdexcept>

namespace impact::bench {

/// One Embree device with one scene, owned (neither copied nor moved): add() the triangle
/// geometries, commit(), then cast rays with first_hit(). Throws std::runtime_error when Embree
/// cannot create its device.
class EmbreeScene {
 public:
  /// `robust` sets RTC_SCENE_FLAG_ROBUST; `monitor`, when not null, becomes the device's memory
  /// monitor before the scene is created (it then sees every allocation of the scene).
  explicit EmbreeScene(bool robust = false, RTCMemoryMonitorFunction monitor = nullptr) {
    device_ = rtcNewDevice(nullptr);
    if (!device_) throw std::runtime_error("rtcNewDevice failed");
    if (monitor) rtcSetDeviceMemoryMonitorFunction(device_, monitor, nullptr);
    scene_ = rtcNewScene(device_);
    rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);
    if (robust) rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);
  }
  ~EmbreeScene() {
    if (scene_) rtcReleaseScene(scene_);
    if (device_) rtcReleaseDevice(device_);
  }
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;

  /// Adds one triangle geometry (geomID: the number of geometries added before it): the vertices
  /// rounded to float, the faces' indices as unsigned.
  void add(const Vertices<double>& V, const Faces& F) {
    RTCGeometry geom = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuildQuality(geom, RTC_BUILD_QUALITY_HIGH);
    auto* v = static_cast<float*>(
        rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), std::size_t(V.rows())));
    auto* f = static_cast<unsigned*>(
        rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), std::size_t(F.rows())));
    for (Eigen::Index i = 0; i < V.rows(); ++i)
      for (int k = 0; k < 3; ++k) v[3 * i + k] = static_cast<float>(V(i, k));
    for (Eigen::Index t = 0; t < F.rows(); ++t)
      for (int k = 0; k < 3; ++k) f[3 * t + k] = static_cast<unsigned>(F(t, k));
    rtcCommitGeometry(geom);
    rtcAttachGeometry(scene_, geom);
    rtcReleaseGeometry(geom);
  }

  /// Builds the scene's hierarchy over the geometries added so far.
  void commit() { rtcCommitScene(scene_); }

  /// The first hit of the ray o + t d, t in [0, t_max], origin and direction rounded to float:
  /// the ray and hit as rtcIntersect1 leaves them (hit.geomID is RTC_INVALID_GEOMETRY_ID when
  /// nothing is hit; otherwise ray.tfar is the hit's t and hit.Ng its unnormalised normal).
  template <class S>
  RTCRayHit first_hit(const Vec3<S>& o, const Vec3<S>& d, float t_max) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh;
    rh.ray.org_x = float(o.x()), rh.ray.org_y = float(o.y()), rh.ray.org_z = float(o.z());
    rh.ray.dir_x = float(d.x()), rh.ray.dir_y = float(d.y()), rh.ray.dir_z = float(d.z());
    rh.ray.tnear = 0.0f;
    rh.ray.tfar = t_max;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.ray.time = 0.0f;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene_, &ctx, &rh);
    return rh;
  }

 private:
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
};

}  // namespace impact::bench
