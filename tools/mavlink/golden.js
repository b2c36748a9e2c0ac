// Golden MAVLink v2 frames from node-mavlink 2.3.0 (an independent implementation) for
// tests/unit/hal/protocol/mavlink_test.cpp. Usage: cd tools/mavlink && npm ci && node golden.js
// Prints one line per frame: NAME HEX.
const { MavLinkProtocolV2, minimal, common } = require('node-mavlink');
const p = new MavLinkProtocolV2(1, 191);  // our system 1, component 191 (onboard computer)
function out(name, msg, seq) { console.log(name, p.serialize(msg, seq).toString('hex')); }

const hb = new minimal.Heartbeat();
hb.type = minimal.MavType.ONBOARD_CONTROLLER; hb.autopilot = minimal.MavAutopilot.INVALID;
hb.baseMode = 0; hb.customMode = 0; hb.systemStatus = minimal.MavState.ACTIVE; hb.mavlinkVersion = 3;
out('heartbeat', hb, 0);

const sp = new common.SetPositionTargetLocalNed();
sp.timeBootMs = 123456; sp.targetSystem = 1; sp.targetComponent = 1; sp.coordinateFrame = 1;
sp.typeMask = 0; sp.x = 1.5; sp.y = -2.25; sp.z = -1.75; sp.vx = 0.5; sp.vy = -0.25; sp.vz = 0.125;
sp.afx = 0.0625; sp.afy = -0.5; sp.afz = 0; sp.yaw = 1.25; sp.yawRate = -0.375;
out('set_position_target_local_ned', sp, 7);

const lp = new common.LocalPositionNed();
lp.timeBootMs = 1000; lp.x = 3.5; lp.y = 4.25; lp.z = -2; lp.vx = 0.5; lp.vy = 0; lp.vz = -0.25;
out('local_position_ned', lp, 200);

const at = new common.Attitude();
at.timeBootMs = 2000; at.roll = 0.125; at.pitch = -0.0625; at.yaw = 2.5; at.rollspeed = 0.01;
at.pitchspeed = -0.02; at.yawspeed = 0.5;
out('attitude', at, 255);

const od = new common.Odometry();
od.timeUsec = 5000000n; od.frameId = 1; od.childFrameId = 12; od.x = 1; od.y = 2; od.z = -3;
od.q = [0.9238795, 0, 0, 0.3826834]; od.vx = 0.5; od.vy = -0.5; od.vz = 0.25; od.rollspeed = 0;
od.pitchspeed = 0.125; od.yawspeed = -0.25;
od.poseCovariance = new Array(21).fill(0); od.poseCovariance[0] = NaN;
od.velocityCovariance = new Array(21).fill(0); od.velocityCovariance[0] = NaN;
od.resetCounter = 2; od.estimatorType = 3; od.quality = 100;
out('odometry', od, 9);
