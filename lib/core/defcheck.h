/* The check value of definition structs (Box2D v3's internalValue): every *_def_default()
 * function sets def.internal_check to AP_DEF_CHECK, and every function that takes a definition
 * refuses one whose field holds anything else, naming the default function in its message
 * ("ap_joint_def 'hinge' was not made by ap_joint_def_default()"). A definition zeroed or
 * written field by field would otherwise compile silently with zeros where the defaults are
 * not zero: no gravity, body 0 as a joint's parent instead of the ground. Copies of a good
 * definition keep the value. */
#ifndef AP_DEFCHECK_H
#define AP_DEFCHECK_H

#define AP_DEF_CHECK 0x41504446   /* "APDF" */

/* The tail of the message for a definition of type `type` that fails the check. */
#define AP_DEF_NOT_DEFAULT(type) "was not made by " type "_default() (start from " type \
  "_default() and set the fields that differ)"

#endif
