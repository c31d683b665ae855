/* tests/test_api's cases for the output files of include/appell/outfile.h: NULL or missing
 * arguments give AP_ERR_ARG (and nothing is written), a function called out of order too. */
#include <errno.h>
#include <string.h>

#include <appell/appell.h>

#include "api_case.h"

void api_cases_io(void) {
  static ap_outfile o;
  static char msg[256];
  static const char data[] = "x\n";
  int err = 0;
  CASE(ap_out_check, "o NULL", ap_out_check(NULL, "x.csv", NULL, 0, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_out_check, "target NULL",
       ap_out_check(&o, NULL, NULL, 0, msg, sizeof msg) == AP_ERR_ARG && o.err == EINVAL);
  CASE(ap_out_check, "target empty", ap_out_check(&o, "", NULL, 0, NULL, 0) == AP_ERR_ARG);
  CASE(ap_out_check, "keep NULL with nkeep 1",
       ap_out_check(&o, "x.csv", NULL, 1, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_out_check, "nkeep < 0", ap_out_check(&o, "x.csv", NULL, -1, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_out_open, "o NULL", ap_out_open(NULL, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_out_open, "not checked",
       (memset(&o, 0, sizeof o), o.fd = -1, ap_out_open(&o, msg, sizeof msg) == AP_ERR_ARG));
  CASE(ap_out_finish, "o NULL", ap_out_finish(NULL, 1, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_out_write_file, "target NULL",
       ap_out_write_file(NULL, data, 2, NULL, 0, &err, msg, sizeof msg) == AP_ERR_ARG &&
           err == EINVAL);
  CASE(ap_out_write_file, "data NULL with len 2",
       ap_out_write_file("never-written.csv", NULL, 2, NULL, 0, &err, msg, sizeof msg) ==
           AP_ERR_ARG && access("never-written.csv", F_OK) != 0);
  /* URDF import (include/appell/urdf.h). */
  static char *yaml = (char *)1;
  static size_t ylen = 1;
  static ap_urdf_def ud;
  static const char *const one_wheel[1] = {"wheel"};
  CASE(ap_urdf_def_default, "defaults",
       (ud = ap_urdf_def_default(), ud.nwheels == 0 && !ud.wheels &&
        ud.wheel_shape == AP_URDF_WHEEL_DISK));
  CASE(ap_urdf_to_scene, "path NULL",
       ap_urdf_to_scene(NULL, NULL, &yaml, &ylen, msg, sizeof msg) == AP_ERR_ARG && !yaml &&
           !ylen);
  CASE(ap_urdf_to_scene, "yaml NULL",
       ap_urdf_to_scene(SCENE_PATH, NULL, NULL, &ylen, msg, sizeof msg) == AP_ERR_ARG);
  CASE(ap_urdf_to_scene, "len NULL, msg NULL",
       ap_urdf_to_scene(SCENE_PATH, NULL, &yaml, NULL, NULL, 0) == AP_ERR_ARG && !yaml);
  CASE(ap_urdf_to_scene, "a directory",
       ap_urdf_to_scene("/", NULL, &yaml, &ylen, msg, sizeof msg) == AP_ERR_ARG && !yaml);
  CASE(ap_urdf_to_scene, "a scene, not XML",
       ap_urdf_to_scene(SCENE_PATH, NULL, &yaml, &ylen, msg, sizeof msg) == AP_ERR_ARG &&
           !yaml && strstr(msg, "XML syntax error"));
  CASE(ap_urdf_to_scene, "def not from ap_urdf_def_default",
       (memset(&ud, 0, sizeof ud),
        ap_urdf_to_scene(SCENE_PATH, &ud, &yaml, &ylen, msg, sizeof msg) == AP_ERR_ARG));
  CASE(ap_urdf_to_scene, "nwheels 1, wheels NULL",
       (ud = ap_urdf_def_default(), ud.nwheels = 1,
        ap_urdf_to_scene(SCENE_PATH, &ud, &yaml, &ylen, msg, sizeof msg) == AP_ERR_ARG));
  CASE(ap_urdf_to_scene, "nwheels -1",
       (ud = ap_urdf_def_default(), ud.wheels = one_wheel, ud.nwheels = -1,
        ap_urdf_to_scene(SCENE_PATH, &ud, &yaml, &ylen, msg, sizeof msg) == AP_ERR_ARG));
  /* The ground of a constraint (include/appell/body.h); BM is the rolling disk (constraint 0
   * rolling), SM a math-level model. */
  static ap_ground_motion gm;
  CASE(ap_model_constraint_ground, "m NULL", ap_model_constraint_ground(NULL, 0, &gm) == AP_ERR_ARG);
  CASE(ap_model_constraint_ground, "math-level model",
       ap_model_constraint_ground(SM, 0, &gm) == AP_ERR_ARG);
  CASE(ap_model_constraint_ground, "c -1", ap_model_constraint_ground(BM, -1, &gm) == AP_ERR_ARG);
  CASE(ap_model_constraint_ground, "c too large",
       ap_model_constraint_ground(BM, 99, &gm) == AP_ERR_ARG);
  CASE(ap_model_constraint_ground, "out NULL", ap_model_constraint_ground(BM, 0, NULL) == AP_ERR_ARG);
  CASE(ap_model_constraint_ground, "the disk's rolling: the plane z = 0",
       ap_model_constraint_ground(BM, 0, &gm) == AP_OK && gm.normal[2] == 1 &&
           gm.sphere_radius == 0);
}
