# Unity builds: a target's sources compiled in batches of a few files each, so that the headers every source pulls
# in (Bullet, Eigen, CLI11, nlohmann-json) are parsed and their templates instantiated once per batch instead of
# once per file. A full build takes a fraction of the time; rebuilding after one edit compiles its batch.
# Sources of one target therefore share a namespace: helpers in anonymous namespaces need distinct names.
option(AFB_UNITY_BUILD "Compile the libraries and afb in batches of sources (unity build)" ON)

function(afb_unity target)
  if(AFB_UNITY_BUILD)
    set_target_properties(${target} PROPERTIES UNITY_BUILD ON UNITY_BUILD_BATCH_SIZE 8)
  endif()
endfunction()
