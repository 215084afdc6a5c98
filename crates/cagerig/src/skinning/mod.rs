//! Skinning S→S'→M': LBS, DQS and CoR (Eq. 1–6).
