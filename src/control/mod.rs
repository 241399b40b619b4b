//! Control laws, one file per paper, Bevy-free: each takes an observation and returns a command.

pub mod geng2015;
pub mod guo2016;
pub mod xu2015;
pub mod xu2019;
pub mod zhang2018;

/// A controller as written in a scene's `controllers` list; each paper's law defines its own
/// `SceneSpec` (which bodies, parameters, sensors) next to the law.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub enum ControllerSpec {
    /// Guo, Song, Li (2016): sliding mode with the cissoid corridor.
    Guo2016(guo2016::SceneSpec),
    /// Geng, Chen, Liang (2015): twisting / modified twisting on the docking ports.
    Geng2015(geng2015::SceneSpec),
    /// Xu, Hu (2015): characteristic-model adaptive control or its PD baseline.
    Xu2015(xu2015::SceneSpec),
    /// Zhang, He, Lü, Wang (2018): differential-game avoidance.
    Zhang2018(zhang2018::SceneSpec),
    /// Xu, Wen, Wei (2019): artificial potential with superquadric obstacle and heart keep-out,
    /// on an air-bearing table.
    Xu2019(xu2019::SceneSpec),
}
