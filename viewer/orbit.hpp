// Camera moves of the viewer's mouse: orbit about the target, pan in the view plane, zoom.
#pragma once
#include "gl/render.hpp"

namespace deformlab::viewer {

// Turns the eye about the target: `yaw` about the world's up axis, `pitch` about the camera's
// right axis (radians), stopping short of looking straight up or down.
void orbit(gl::Camera& c, float yaw, float pitch);
// Moves eye and target so that the point under the cursor follows a drag of (dx, dy) pixels
// in a view `h` pixels high.
void pan(gl::Camera& c, float dx, float dy, int h);
// Scales the eye's distance from the target by `factor`.
void zoom(gl::Camera& c, float factor);

}  // namespace deformlab::viewer
